// Memory of a live process under a long flood (issue 21): in a private network namespace, a
// sweepmap process (the assembler or the mapper, rig A) receives, for --seconds, good traffic
// (40 scans/s and a scan window every 5 s, stamped with the wall clock) mixed with hostile
// datagrams from 16 senders (liblcm 1.3.1's crash datagrams, malformed headers, first
// fragments of 100 kB messages that never complete, and well-formed messages that break
// decoders). Its resident memory (VmRSS) is sampled every second; printed: at the start of the
// flood, the largest, and at the end, and whether the process lived. Exit 1 if it died.
//
// bench_flood [--seconds 600] [--process assembler|mapper] [--rate 10000]
// Not part of `make bench` (10 minutes by default); run it by hand or in the background.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "core/lcm_schema.hpp"
#include "net/udpm_receiver.hpp"
#include "processes/channels.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "tools/bench/hostile_traffic.hpp"
#include "tools/bench/proc_stats.hpp"
#include "tools/ops/netns.hpp"
#include "tools/ops/process_group.hpp"

namespace {

using namespace sweepmap;
using hostile::Bytes;
namespace fs = std::filesystem;

struct FloodOptions {
  double seconds = 600.0;
  std::string process = "assembler";
  int rate = 10000;  // hostile datagrams per second
};

int64_t wallUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

template <class T>
Bytes encode(const T& m) {
  Bytes b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

Bytes scan(int64_t seq) {
  lidar_scan_t s{};
  s.utime = wallUs();
  s.seq = seq;
  s.angle_min_rad = -2.356f;
  s.angle_increment_rad = 0.00436f;
  s.time_increment_ns = 23000;
  s.range_min_m = 0.06f;
  s.range_max_m = 10.0f;
  s.nranges = 1081;
  s.ranges_m.assign(1081, 2.5f);
  s.device_stamp = -1;
  return encode(s);
}

Bytes window(int64_t id, int64_t start_us, int64_t end_us) {
  scan_window_t w{};
  w.utime = end_us;
  w.sweep_id = id;
  w.mode = 1;
  w.start_utime = start_us;
  w.end_utime = end_us;
  w.angular_velocity_rad_s = 0.628;
  w.sweep_angle_rad = 3.14159;
  w.action_sequence = scan_window_t::IMPROVED;
  return encode(w);
}

// One second's hostile datagrams: `rate` of them, cycling through the kinds.
std::vector<Bytes> hostileSecond(int rate, uint32_t second) {
  const std::vector<std::string> channels = {"LIDAR_SCAN", "SCAN_WINDOW", "SWEEP_CLOUD", "MAP_SAVE",
                                             "MOTOR_STATE"};
  std::vector<Bytes> kinds = hostile::malformedDatagrams(channels, 200, second);
  for (Bytes& d : hostile::datagramsOf(hostile::decoderBreakers(), second * 64)) {
    kinds.push_back(std::move(d));
  }
  std::vector<Bytes> out;
  for (int i = 0; i < rate; ++i) {
    if (i % 4 == 0) {  // a new message's first fragment: held until it expires or is evicted
      out.push_back(hostile::openFragment("SWEEP_CLOUD", second * 1000003u + i));
    } else {
      out.push_back(kinds[static_cast<size_t>(i) % kinds.size()]);
    }
  }
  return out;
}

struct Rss {
  int64_t start_kib = 0, max_kib = 0, end_kib = 0;
  int64_t peak_kib = 0;  // VmHWM: the kernel's own peak, between the samples too
};

// The target's last status message (its counters), heard through sweepmap's receive path. The
// flood's own forged status messages (invalid, or naming another process) are not it.
class StatusListener {
 public:
  explicit StatusListener(const std::string& process) : receiver_(kDefaultLcmUrl) {
    receiver_.subscribe("STATUS_.*",
                        [this, process](const std::string&, const uint8_t* d, size_t n) {
                          // Validated first, as every node does: the flood's 2^26 counters would
                          // take lcm-gen's decoder to gigabytes.
                          process_status_t s;
                          if (LcmSchema::builtIn().validate(d, n).empty() &&
                              s.decode(d, 0, static_cast<int>(n)) > 0 && s.process == process) {
                            last_ = s;
                          }
                        });
  }
  void poll() {
    while (receiver_.handleTimeout(0) > 0) {
    }
  }
  // "name value" of the non-zero counters whose name starts with `prefix`.
  std::string counters(const std::string& prefix) const {
    if (!last_) return "no status heard";
    std::string out;
    for (int i = 0; i < last_->ncounters; ++i) {
      if (last_->counter_names[i].rfind(prefix, 0) != 0 || last_->counter_values[i] == 0) continue;
      out += (out.empty() ? "" : ", ") + last_->counter_names[i] + " " +
             std::to_string(last_->counter_values[i]);
    }
    return out;
  }

 private:
  net::UdpmReceiver receiver_;
  std::optional<process_status_t> last_;
};

// Floods for o.seconds, a tick every 25 ms (a scan each, hostile datagrams spread evenly), and
// samples the target's RSS every second. False if the target died.
bool flood(ProcessGroup& group, pid_t target, const FloodOptions& o, StatusListener& status,
           Rss* rss, uint64_t* sent) {
  std::vector<std::unique_ptr<hostile::MulticastSender>> senders;
  for (int i = 0; i < 16; ++i) {
    senders.push_back(std::make_unique<hostile::MulticastSender>("239.255.76.67", 7667));
  }
  hostile::MulticastSender& good = *senders[0];
  rss->start_kib = rss->max_kib = statusKib(target, "VmRSS:");
  const auto t0 = BenchClock::now();
  int64_t tick = 0, window_start = wallUs();
  std::vector<Bytes> second_batch;
  while (secondsSince(t0) < o.seconds) {
    if (!group.running(target)) return false;
    if (tick % 40 == 0) {
      second_batch = hostileSecond(o.rate, static_cast<uint32_t>(tick / 40));
      const int64_t kib = statusKib(target, "VmRSS:");
      rss->max_kib = std::max(rss->max_kib, kib);
      rss->end_kib = kib;
      if (tick % (40 * 60) == 0) {  // a line a minute: growth or a plateau
        std::printf("%4lld s: RSS %.1f MiB, CPU %.1f s\n", static_cast<long long>(tick / 40),
                    kib / 1024.0, processCpuSeconds(target));
        std::fflush(stdout);
      }
    }
    *sent += good.send(hostile::datagramsOf({{"LIDAR_SCAN", scan(tick)}}, tick), 0);
    if (tick % 200 == 199) {
      const int64_t now = wallUs();
      *sent += good.send(
          hostile::datagramsOf({{"SCAN_WINDOW", window(tick / 200, window_start, now)}}, tick), 0);
      window_start = now;
    }
    const size_t per_tick = second_batch.size() / 40, from = (tick % 40) * per_tick;
    for (size_t i = from; i < from + per_tick; ++i) {
      *sent += senders[i % senders.size()]->send({second_batch[i]}, 0);
    }
    status.poll();
    ++tick;
    std::this_thread::sleep_until(t0 + std::chrono::microseconds(25000 * tick));
  }
  rss->end_kib = statusKib(target, "VmRSS:");
  rss->peak_kib = statusKib(target, "VmHWM:");
  rss->max_kib = std::max(rss->max_kib, rss->end_kib);
  return group.running(target);
}

}  // namespace

int main(int argc, char** argv) {
  FloodOptions o;
  CLI::App app{
      "Flood a live sweepmap process with good and hostile LCM traffic in a private "
      "network namespace and sample its resident memory"};
  app.add_option("--seconds", o.seconds, "how long")->capture_default_str();
  app.add_option("--process", o.process, "the process flooded")
      ->check(CLI::IsMember({"assembler", "mapper"}))
      ->capture_default_str();
  app.add_option("--rate", o.rate, "hostile datagrams per second")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::string why;
  if (!enterPrivateNetwork(&why)) {
    std::fprintf(stderr, "bench_flood: no private network namespace: %s\n", why.c_str());
    return 2;
  }
  const fs::path bin = fs::canonical("/proc/self/exe").parent_path();
  const std::string log = (fs::temp_directory_path() / "bench_flood_target.txt").string();
  ProcessGroup group;
  const pid_t target =
      group.start(o.process, {(bin / ("sweepmap-" + o.process)).string(), "--rig", "rig_a"}, log);
  std::this_thread::sleep_for(std::chrono::seconds(2));  // started and subscribed
  Rss rss;
  uint64_t sent = 0;
  StatusListener status(o.process);
  const bool alive = flood(group, target, o, status, &rss, &sent);
  const double cpu_s = processCpuSeconds(target);
  std::printf(
      "flood of sweepmap-%s for %.0f s (%d hostile datagrams/s from 16 senders, 40 scans/s): "
      "%llu datagrams sent; RSS at the start %.1f MiB, largest sample %.1f MiB, at the end "
      "%.1f MiB, peak (VmHWM) %.1f MiB; %s (its output: %s)\nits last status: %s\n",
      o.process.c_str(), o.seconds, o.rate, static_cast<unsigned long long>(sent),
      rss.start_kib / 1024.0, rss.max_kib / 1024.0, rss.end_kib / 1024.0, rss.peak_kib / 1024.0,
      alive ? "it lived" : "IT DIED", log.c_str(), status.counters("net_").c_str());
  // What the flooded process spent on everything it received (the kernel's share included):
  // the receive path's cost per datagram end to end.
  std::printf(
      "its CPU: %.1f s in %.0f s (%.1f %% of one core), %.2f us per datagram sent: "
      "%.0f datagrams/s per core\n",
      cpu_s, o.seconds, 100.0 * cpu_s / o.seconds, 1e6 * cpu_s / static_cast<double>(sent),
      static_cast<double>(sent) / cpu_s);
  if (alive) group.stop(target, 10.0);
  return alive ? 0 : 1;
}
