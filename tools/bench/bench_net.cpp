// The receive path's costs (issue 21), printed, nothing asserted: one-file tool over the net
// library. Figures per core (one thread):
//  - datagrams the validator refuses per second (the 131-byte crash datagram and random
//    headers), against copying the same datagrams (the floor: memcpy of the bytes);
//  - good traffic reassembled per second (a 1081-ray scan in one datagram, a 200 kB sweep
//    chunk in 4 fragments);
//  - the CPU cost of signing and verifying at the on-board rates (40 scans/s, 400 IMU/s,
//    100 wheel readings/s), as a share of one core;
//  - memory held while a flood of spoofed senders opens large messages.
// bench_net [seconds per figure, default 1]
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "net/lcm_datagram.hpp"
#include "net/message_auth.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using Bytes = std::vector<uint8_t>;
using namespace sweepmap::net;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Runs `step` for about `seconds`; returns the calls per second.
template <class F>
double rate(double seconds, F step) {
  const auto t0 = Clock::now();
  uint64_t n = 0;
  while (true) {
    for (int k = 0; k < 1000; ++k) step(n++);
    const double s = secondsSince(t0);
    if (s >= seconds) return static_cast<double>(n) / s;
  }
}

Bytes crashDatagram(uint32_t seqno) {
  Bytes b = {'L', 'C', '0', '3', 0, 0, 0, 0, 0, 1, 0x86, 0xa0, 0xff, 0xff, 0xff, 0xff, 0, 0, 0, 2};
  for (int i = 0; i < 4; ++i) b[4 + i] = static_cast<uint8_t>(seqno >> (24 - 8 * i));
  for (char c : std::string("LIDAR_SCAN")) b.push_back(static_cast<uint8_t>(c));
  b.push_back(0);
  b.resize(131, 0x41);
  return b;
}

// What the reassembler hands out is read, so that the compiler cannot drop the work.
volatile uint64_t g_sink = 0;
void consume(const std::optional<LcmMessage>& m) {
  if (m && !m->data.empty()) g_sink = g_sink + m->data.size() + m->data[m->data.size() / 2];
}

// Resident memory now [kB] (/proc/self/statm), not the peak: the flood's own share.
long rssKb() {
  long pages = 0, resident = 0;
  if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

// Hostile datagrams (the crash datagram, half with random header bytes) refused per second,
// against copying them.
void benchRefusals(double seconds) {
  std::mt19937 rng(1);
  std::vector<Bytes> hostile;
  for (uint32_t i = 0; i < 4096; ++i) {
    Bytes b = crashDatagram(i);
    if (i % 2) {
      for (int e = 0; e < 4; ++e) b[rng() % 24] = static_cast<uint8_t>(rng());
    }
    hostile.push_back(std::move(b));
  }
  LcmReassembler reassembler;
  const double refused = rate(seconds, [&](uint64_t n) {
    const Bytes& d = hostile[n % hostile.size()];
    consume(reassembler.feed(d.data(), d.size(), SenderId{static_cast<uint32_t>(n % 8), 1},
                             static_cast<int64_t>(n)));
  });
  Bytes sink(256);
  const double copied = rate(seconds, [&](uint64_t n) {
    const Bytes& d = hostile[n % hostile.size()];
    std::memcpy(sink.data(), d.data(), d.size());
    sink[0] ^= static_cast<uint8_t>(n);
  });
  std::printf(
      "hostile datagrams validated and dropped: %.2f M/s per core (copying them: %.2f M/s)\n",
      refused / 1e6, copied / 1e6);
}

// Good traffic reassembled per second: a scan in one datagram, a sweep chunk in fragments.
void benchGoodTraffic(double seconds) {
  const Bytes scan(4400, 7), chunk(200000, 9);
  const auto scan_d = encodeLcmDatagrams("LIDAR_SCAN", scan.data(), scan.size(), 1);
  const auto chunk_d = encodeLcmDatagrams("SWEEP_CLOUD", chunk.data(), chunk.size(), 1);
  LcmReassembler good;
  const double scans = rate(seconds, [&](uint64_t n) {
    consume(good.feed(scan_d[0].data(), scan_d[0].size(), SenderId{1, 1}, static_cast<int64_t>(n)));
  });
  const double chunks = rate(seconds / 10, [&](uint64_t n) {
    for (const Bytes& d : chunk_d) {
      consume(good.feed(d.data(), d.size(), SenderId{2, 1}, static_cast<int64_t>(n)));
    }
  });
  std::printf(
      "good traffic: %.0f scans/s (4.4 kB, one datagram), %.0f sweep chunks/s (200 kB, %zu "
      "fragments) per core\n",
      scans, chunks, chunk_d.size());
}

// Sign + verify per second by message size, and the share of a core at the on-board rates.
void benchSigning(double seconds) {
  std::array<uint8_t, kAuthKeyBytes> key{};
  key.fill(3);
  const MessageAuth auth(key);
  const Bytes scan(4400, 7), imu(112, 1), ticks(40, 2);
  double signed_rate[3];
  const Bytes* payloads[3] = {&scan, &imu, &ticks};
  for (int k = 0; k < 3; ++k) {
    signed_rate[k] = rate(seconds, [&](uint64_t) {
      const Bytes s = auth.sign("CH", payloads[k]->data(), payloads[k]->size());
      const auto verified = auth.verify("CH", s.data(), s.size());
      if (!verified) std::abort();
      g_sink = g_sink + *verified + s.back();
    });
  }
  // On-board rates: 40 scans/s, 400 IMU samples/s, 100 wheel readings/s.
  const double share = 40.0 / signed_rate[0] + 400.0 / signed_rate[1] + 100.0 / signed_rate[2];
  std::printf(
      "sign+verify: %.0f scans/s, %.0f IMU/s, %.0f wheel readings/s per core; at the "
      "on-board rates %.3f %% of one core (x86 of this machine)\n",
      signed_rate[0], signed_rate[1], signed_rate[2], 100.0 * share);
}

// Memory while spoofed senders each open a large message.
void benchFlood() {
  const long rss0 = rssKb();
  LcmReassembler flooded;
  for (uint32_t i = 0; i < 2'000'000; ++i) {
    Bytes d = crashDatagram(i);
    d[12] = d[13] = d[14] = d[15] = 0;  // offset 0: a valid first fragment of a 100 kB message
    flooded.feed(d.data(), d.size(), SenderId{i % 100000, static_cast<uint16_t>(i)},
                 static_cast<int64_t>(i));
  }
  std::printf(
      "flood of 2 M first fragments from 100 000 spoofed senders: %zu messages pending, "
      "%zu bytes held, RSS %+ld kB\n",
      flooded.pendingMessages(), flooded.pendingBytes(), rssKb() - rss0);
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 1.0;
  benchRefusals(seconds);
  benchGoodTraffic(seconds);
  benchSigning(seconds);
  benchFlood();
  return 0;
}
