#include "tools/bench/bench_devices.hpp"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <optional>
#include <thread>

#include "core/device_uri.hpp"
#include "drivers/lidar_sessions.hpp"
#include "processes/channels.hpp"
#include "rigs/rig_file.hpp"
#include "tools/bench/proc_stats.hpp"
#include "tools/emulate/devices.hpp"
#include "tools/ops/netns.hpp"
#include "tools/ops/process_group.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

struct Protocol {
  const char* name;
  EmulatedModel model;
  DeviceProtocol protocol;
  const char* rig;
  std::string start;              // what the host sends to start the stream
  std::vector<std::string> sets;  // the rig's lidar section for this device
};

// Synthetic scans on the rig's grid: a room-like range profile, every ray a return.
ScanSource syntheticScans(const LidarConfig& lidar) {
  auto next = std::make_shared<int64_t>(0);
  return [lidar, next](int64_t now_us) {
    std::vector<Scan2D> out;
    const double period_us = 1e6 / lidar.scan_rate_hz;
    for (;;) {
      const auto start = static_cast<int64_t>(std::llround(double(*next) * period_us));
      if (start + period_us > now_us) break;
      Scan2D s;
      s.seq = (*next)++;
      s.utime = start;
      s.angle_min_rad = lidar.angle_min_deg * M_PI / 180.0;
      s.angle_increment_rad = lidar.angle_increment_deg * M_PI / 180.0;
      s.time_increment_ns = static_cast<int64_t>(lidar.rayPeriodS() * 1e9);
      s.range_min_m = lidar.range_min_m;
      s.range_max_m = lidar.range_max_m;
      s.ranges_m.resize(static_cast<size_t>(lidar.beam_count));
      for (int i = 0; i < lidar.beam_count; ++i) {
        s.ranges_m[static_cast<size_t>(i)] =
            static_cast<float>(2.0 + 1.5 * std::sin(0.013 * i + 0.1 * double(s.seq)));
      }
      out.push_back(std::move(s));
    }
    return out;
  };
}

void benchDecoders(const DevicesBenchOptions& o, std::ostream& out) {
  const std::vector<Protocol> protocols = {
      {"scip (UST-10LX, ME: ranges + intensities)",
       EmulatedModel::kUst10lx,
       DeviceProtocol::kScip,
       "rig_a",
       "BM\nME0000108000000\n",
       {}},
      {"ydlidar (X4)",
       EmulatedModel::kX4,
       DeviceProtocol::kYdlidarX4,
       "rig_b",
       std::string("\xA5\x60", 2),
       {}},
      {"rplidar (A1, standard scan)",
       EmulatedModel::kRplidarA1,
       DeviceProtocol::kRplidar,
       "rig_b",
       std::string("\xA5\x20", 2),
       // An A1: 360 samples per turn at 5.5 Hz (1980 samples/s), 0.15-12 m.
       {"lidar.beam_count=360", "lidar.angle_min_deg=-180", "lidar.angle_increment_deg=1",
        "lidar.steps_per_revolution=360", "lidar.scan_rate_hz=5.5", "lidar.range_min_m=0.15"}},
  };
  out << "decoders (the driver's session: decode, scan assembly, timing; one thread):\n";
  for (const Protocol& p : protocols) {
    LidarConfig lidar = loadRig(p.rig, p.sets).lidar();
    const double stream_s = 10.0;
    // The device's own bytes for 10 s of streaming.
    std::unique_ptr<EmulatedLidar> device =
        makeEmulatedLidar(p.model, syntheticScans(lidar), EmulatedClock{}, 0);
    std::string bytes;
    device->receive(reinterpret_cast<const uint8_t*>(p.start.data()), p.start.size(), 1000, &bytes);
    const size_t reply_bytes = bytes.size();
    for (int64_t t = 1000; t <= static_cast<int64_t>(stream_s * 1e6); t += 1000) {
      device->advance(t, &bytes);
    }
    const double device_rate = double(bytes.size() - reply_bytes) / stream_s;  // bytes/s
    // Decode it in 4 KiB chunks, again and again for at least decode_min_s.
    int64_t scans = 0, passes = 0;
    const auto t0 = BenchClock::now();
    double wall = 0.0;
    do {
      std::unique_ptr<LidarSession> session = makeLidarSession(p.protocol, lidar, SessionOptions{});
      std::vector<Scan2D> got;
      std::vector<std::string> errors;
      int64_t arrival = 1'700'000'000'000'000 + passes * 20'000'000;
      for (size_t at = 0; at < bytes.size(); at += 4096) {
        const size_t n = std::min<size_t>(4096, bytes.size() - at);
        arrival += static_cast<int64_t>(double(n) / device_rate * 1e6);
        got.clear();
        session->onBytes(reinterpret_cast<const uint8_t*>(bytes.data()) + at, n, arrival, &got,
                         &errors);
        scans += static_cast<int64_t>(got.size());
      }
      ++passes;
      wall = secondsSince(t0);
    } while (wall < o.decode_min_s);
    const double mb_s = double(bytes.size()) * double(passes) / wall / 1e6;
    const double scans_s = double(scans) / wall;
    out << "  " << std::left << std::setw(44) << p.name << std::right << std::setprecision(1)
        << std::setw(8) << mb_s << " MB/s " << std::setw(9) << std::setprecision(0) << scans_s
        << " scans/s; device " << std::setprecision(1) << device_rate / 1e3 << " kB/s, "
        << std::setprecision(1) << lidar.scan_rate_hz << " scans/s -> " << std::setprecision(0)
        << mb_s * 1e6 / device_rate << "x its data rate\n";
  }
}

// The CPU share of `pid` (and of the emulator feeding it, if any) over `seconds`, from /proc,
// with its thread switches and peak RSS; then stops both.
ProcessLoad measureProcess(ProcessGroup& procs, const std::string& name, pid_t pid, pid_t emulator,
                           double seconds, std::ostream& out) {
  const double cpu0 = processCpuSeconds(pid), emu0 = processCpuSeconds(emulator);
  const int64_t switches0 = contextSwitches(pid);
  const auto t0 = BenchClock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  const double wall = secondsSince(t0);
  const double share = (processCpuSeconds(pid) - cpu0) / wall;
  const double emu_share = (processCpuSeconds(emulator) - emu0) / wall;
  const double switches = double(contextSwitches(pid) - switches0) / wall;
  const int64_t rss = statusKib(pid, "VmHWM:");
  procs.stop(pid, 5.0);
  if (emulator > 0) procs.stop(emulator, 5.0);
  out << std::setprecision(2) << "  " << name << " " << share * 100.0 << " % of a core over "
      << std::setprecision(1) << wall << " s (" << std::setprecision(0) << switches
      << " thread switches/s, peak RSS " << std::setprecision(1) << rss / 1024.0 << " MiB)";
  if (emulator > 0) out << "; the emulator " << std::setprecision(1) << emu_share * 100.0 << " %";
  out << "\n";
  return {name, "", share, rss};
}

// Whether the process benches can run here (the executables, a private network namespace,
// entered now); says why not.
bool canRunProcesses(const DevicesBenchOptions& o, std::ostream& out) {
  if (o.bin_dir.empty()) {
    out << "  skipped: executables not found\n";
    return false;
  }
  std::string why;
  if (!enterPrivateNetwork(&why)) {
    out << "  skipped: no private network namespace (" << why << ")\n";
    return false;
  }
  return true;
}

// sweepmap-lidar driving the emulated UST-10LX over loopback TCP, measured from /proc.
std::optional<ProcessLoad> benchLidarProcess(const DevicesBenchOptions& o, std::ostream& out) {
  out << "sweepmap-lidar process (real SCIP driver, emulated UST-10LX at 40 Hz over loopback "
         "TCP, private network namespace; share of one core = CPU s / wall s):\n";
  if (!canRunProcesses(o, out)) return std::nullopt;
  const fs::path bin = o.bin_dir;
  const std::string url = kDefaultLcmUrl;
  ProcessGroup procs;
  const pid_t emulator = procs.start("emulator",
                                     {(bin / "sweepmap").string(), "emulate", "ust10lx", "--listen",
                                      "127.0.0.1:10940", "--rig", "rig_a"},
                                     "/dev/null");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const pid_t lidar = procs.start("lidar",
                                  {(bin / "sweepmap-lidar").string(), "--rig", "rig_a", "--device",
                                   "scip://127.0.0.1:10940", "--lcm-url", url},
                                  "/dev/null");
  std::this_thread::sleep_for(std::chrono::seconds(2));  // connected, clock anchored
  ProcessLoad load = measureProcess(procs, "sweepmap-lidar", lidar, emulator, o.process_s, out);
  load.what = "UST-10LX, SCIP over TCP, 40 Hz";
  return load;
}

// sweepmap-motor sweeping without pause in mode 7 (MOTOR_STATE at the rig's status rate, a
// SCAN_WINDOW per sweep) on the simulated stepper, measured from /proc. The real stepper adds
// the GPIO step generator's thread (benchStepper) in place of the simulation.
std::optional<ProcessLoad> benchMotorProcess(const DevicesBenchOptions& o, std::ostream& out) {
  out << "sweepmap-motor process (simulated stepper and switch, mode-7 sweeps without end; "
         "share of one core):\n";
  if (!canRunProcesses(o, out)) return std::nullopt;
  const fs::path bin = o.bin_dir;
  ProcessGroup procs;
  const pid_t motor =
      procs.start("motor",
                  {(bin / "sweepmap-motor").string(), "--rig", "rig_a", "--sim", "--set",
                   "motor.mode=7", "--sweeps", "0", "--lcm-url", kDefaultLcmUrl},
                  "/dev/null");
  std::this_thread::sleep_for(std::chrono::seconds(2));  // homed, sweeping
  ProcessLoad load = measureProcess(procs, "sweepmap-motor", motor, -1, o.process_s, out);
  load.what = "sim stepper, mode 7";
  return load;
}

// sweepmap-odometry reading both of rig B's devices (the real HI219 and wheel board drivers)
// from the emulators on pseudo-terminals, at 400 Hz IMU (the 0x91 record; a real HI219 needs
// 460800 baud for that, so the URI says so) and 100 Hz wheels, measured from /proc.
std::optional<ProcessLoad> benchOdometryProcess(const DevicesBenchOptions& o, std::ostream& out) {
  out << "sweepmap-odometry process (real HI219 and wheel board drivers, emulated devices on "
         "ptys: 400 Hz IMU, 100 Hz wheels; share of one core):\n";
  if (!canRunProcesses(o, out)) return std::nullopt;
  const fs::path bin = o.bin_dir;
  const fs::path dir = fs::temp_directory_path() / ("sweepmap_bench_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string imu = (dir / "hi219").string(), board = (dir / "wheelboard").string();
  const std::vector<std::string> sets = {
      "--set", "sim.imu_rate_hz=400",
      "--set", "sim.wheel_ticks_rate_hz=100",
      "--set", "sim.duration_s=" + std::to_string(o.process_s + 30.0)};
  ProcessGroup procs;
  std::vector<std::string> emu_argv = {(bin / "sweepmap").string(),
                                       "emulate",
                                       "hi219,wheel-board",
                                       "--pty",
                                       "--link",
                                       imu,
                                       "--link",
                                       board,
                                       "--rig",
                                       "rig_b"};
  emu_argv.insert(emu_argv.end(), sets.begin(), sets.end());
  const pid_t emulator = procs.start("emulator", emu_argv, "/dev/null");
  for (int i = 0; i < 100 && !(fs::exists(imu) && fs::exists(board)); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::vector<std::string> odo_argv = {(bin / "sweepmap-odometry").string(),
                                       "--rig",
                                       "rig_b",
                                       "--imu-device",
                                       "hi219://" + imu + "?baud=460800",
                                       "--wheels-device",
                                       "wheelboard://" + board,
                                       "--lcm-url",
                                       kDefaultLcmUrl};
  odo_argv.insert(odo_argv.end(), sets.begin(), sets.end());
  const pid_t odometry = procs.start("odometry", odo_argv, "/dev/null");
  std::this_thread::sleep_for(std::chrono::seconds(2));  // connected, clocks synced
  ProcessLoad load =
      measureProcess(procs, "sweepmap-odometry", odometry, emulator, o.process_s, out);
  load.what = "HI219 400 Hz + wheel board 100 Hz, serial";
  fs::remove_all(dir);
  return load;
}

}  // namespace

int benchDevices(const DevicesBenchOptions& options, std::ostream& out,
                 std::vector<ProcessLoad>* loads) {
  benchDecoders(options, out);
  for (const auto& bench : {benchMotorProcess, benchLidarProcess, benchOdometryProcess}) {
    const std::optional<ProcessLoad> load = bench(options, out);
    if (load && loads) loads->push_back(*load);
  }
  return 0;
}

}  // namespace sweepmap
