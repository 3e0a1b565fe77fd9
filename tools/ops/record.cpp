#include "tools/ops/record.hpp"

#include <sys/statvfs.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <thread>

#include "processes/live_runner.hpp"
#include "processes/sd_notify.hpp"
#include "tools/ops/process_group.hpp"

namespace sweepmap {
std::string recordChannels(const std::string& preset) {
  if (preset == "all") return ".*";
  if (preset == "raw") {
    return "LIDAR_SCAN|MOTOR_STATE|MOTOR_SWITCH|SCAN_WINDOW|WHEEL_TICKS|IMU|WHEEL_CMD|PROFILE|"
           "STATUS_.*|"
           "TRUTH_.*";
  }
  throw std::invalid_argument("--preset must be raw or all, not '" + preset + "'");
}

double freeMb(const std::string& path) {
  struct statvfs s {};
  if (::statvfs(path.c_str(), &s) != 0) return -1.0;
  return static_cast<double>(s.f_bavail) * static_cast<double>(s.f_frsize) / 1e6;
}

int runRecord(const RecordOptions& o) {
  namespace fs = std::filesystem;
  std::string channels;
  try {
    channels = recordChannels(o.preset);
  } catch (const std::invalid_argument& e) {
    std::cerr << "record: " << e.what() << "\n";
    return 2;
  }
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec) {
    std::cerr << "record: cannot create " << o.out << ": " << ec.message() << "\n";
    return 4;  // an I/O failure (core/exit_codes.hpp)
  }
  const double free0 = freeMb(o.out);
  if (free0 >= 0 && free0 < o.min_free_mb) {
    std::cerr << "record: only " << std::lround(free0) << " MB free on " << o.out
              << ", below --min-free-mb " << o.min_free_mb << "; not starting\n";
    return 4;
  }
  const std::string file = (fs::path(o.out) / o.name).string();
  std::vector<std::string> argv = {"lcm-logger", "--lcm-url=" + o.lcm_url, "-c", channels, "-q"};
  if (o.split_mb > 0) {
    argv.insert(argv.end(), {"-i", "--split-mb=" + std::to_string(o.split_mb)});
  } else {
    argv.push_back("-f");
  }
  argv.push_back(file);
  installStopSignals();
  ProcessGroup procs;
  pid_t logger = -1;
  try {
    logger = procs.start("lcm-logger", argv);
  } catch (const std::exception& e) {
    std::cerr << "record: " << e.what() << "\n";
    return 2;
  }
  std::cout << "record: " << o.preset << " channels to " << file << (o.split_mb > 0 ? ".NN" : "")
            << " (stops below " << o.min_free_mb << " MB free)\n";
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  // Under systemd or `sweepmap launch`: ready once lcm-logger runs, alive from this loop.
  SdNotifier notifier;
  notifier.ready();
  while (!stopRequested()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    notifier.alive();
    if (!procs.running(logger)) {
      std::cerr << "record: lcm-logger ended (status " << procs.wait(logger, 0) << ")\n";
      return 4;
    }
    const double free = freeMb(o.out);
    if (free >= 0 && free < o.min_free_mb) {
      std::cerr << "record: stopped: " << std::lround(free) << " MB free on " << o.out
                << ", below --min-free-mb " << o.min_free_mb
                << " (the log is closed after its last complete event)\n";
      status = 4;
      break;
    }
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (o.duration_s > 0 && elapsed >= o.duration_s) break;
  }
  notifier.stopping();
  const int rc = procs.stop(logger, 10.0);
  if (rc != 0 && status == 0) {
    std::cerr << "record: lcm-logger exited with status " << rc << "\n";
    return 4;
  }
  return status;
}

}  // namespace sweepmap
