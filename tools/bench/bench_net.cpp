// The receive path's costs (issue 21), printed, nothing asserted: one-file tool over the net
// library. Figures per core (one thread):
//  - datagrams the validator refuses per second (the 131-byte crash datagram and random
//    headers), against copying the same datagrams (the floor: memcpy of the bytes);
//  - good traffic reassembled per second (a 1081-ray scan in one datagram, a 200 kB sweep
//    chunk in 4 fragments);
//  - the CPU cost of signing and verifying at each rig's on-board rates (what its on-board
//    processes publish), as a share of one core;
//  - memory held while a flood of spoofed senders opens large messages.
// bench_net [seconds per figure, default 1]
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
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

// What each rig's on-board processes publish (sweepmap sim and replay of each rig, the
// rig files' rates): channel, messages per second, bytes per message. Rig A: the UST-10LX's
// scans at 40 Hz and the motor's state at 10 Hz; rig B: the X4's scans at 7 Hz, the IMU at
// 200 Hz, the wheel board at 50 Hz and the EKF's two poses at 50 Hz; rig C: profiles at the
// sensor's full-window 170 Hz and the turntable's state. Each also publishes ~2 status
// messages a second.
struct Stream {
  const char* channel;
  double per_s;
  size_t bytes;
};
struct OnBoard {
  const char* rig;
  std::vector<Stream> streams;
};
const std::vector<OnBoard>& onBoardRates() {
  static const std::vector<OnBoard> rigs = {
      {"rig A", {{"LIDAR_SCAN", 40, 4388}, {"MOTOR_STATE", 10, 65}, {"STATUS", 2, 64}}},
      {"rig B",
       {{"LIDAR_SCAN", 7, 2920},
        {"IMU", 200, 88},
        {"WHEEL_TICKS", 50, 32},
        {"ODOMETRY_POSE", 50, 137},
        {"WHEEL_ODOMETRY", 50, 137},
        {"STATUS", 2, 76}}},
      {"rig C", {{"PROFILE", 170, 8227}, {"MOTOR_STATE", 10, 65}, {"STATUS", 2, 64}}}};
  return rigs;
}

// Signing (each publisher) and verifying (each receiver) per second, by message size; and for
// each rig, the share of one core that signing all it publishes, and verifying it once, take.
void benchSigning(double seconds) {
  std::array<uint8_t, kAuthKeyBytes> key{};
  key.fill(3);
  const MessageAuth auth(key);
  std::map<size_t, std::pair<double, double>> per_s;  // bytes -> sign/s, verify/s
  for (const OnBoard& rig : onBoardRates()) {
    for (const Stream& s : rig.streams) per_s[s.bytes];
  }
  for (auto& [bytes, r] : per_s) {
    const Bytes payload(bytes, 7);
    r.first = rate(seconds / 4, [&](uint64_t) {
      const Bytes s = auth.sign("CHANNEL", payload.data(), payload.size());
      g_sink = g_sink + s.back();
    });
    const Bytes signed_payload = auth.sign("CHANNEL", payload.data(), payload.size());
    r.second = rate(seconds / 4, [&](uint64_t) {
      const auto verified = auth.verify("CHANNEL", signed_payload.data(), signed_payload.size());
      if (!verified) std::abort();
      g_sink = g_sink + *verified;
    });
  }
  std::printf("sign: %.0f/s of 4.4 kB scans, %.0f/s of 88 B IMU samples per core\n",
              per_s[4388].first, per_s[88].first);
  for (const OnBoard& rig : onBoardRates()) {
    double sign = 0.0, verify = 0.0, messages = 0.0, bytes = 0.0;
    for (const Stream& s : rig.streams) {
      sign += s.per_s / per_s[s.bytes].first;
      verify += s.per_s / per_s[s.bytes].second;
      messages += s.per_s;
      bytes += s.per_s * static_cast<double>(s.bytes);
    }
    std::printf(
        "%s on board (%.0f messages/s, %.0f kB/s): signing %.3f %% of one core, verifying "
        "once %.3f %% (x86 of this machine)\n",
        rig.rig, messages, bytes / 1e3, 100.0 * sign, 100.0 * verify);
  }
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
