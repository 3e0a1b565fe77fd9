// Real-device part of `sweepmap bench`: each protocol decoder's throughput (the driver's
// session: decode + scan assembly + timing) against the device's own data rate, and the CPU
// share and peak RSS of the real sweepmap-lidar process driving an emulated UST-10LX at 40 Hz
// over loopback TCP, of sweepmap-odometry reading the emulated HI219 (400 Hz) and wheel board
// (100 Hz) on ptys, and of sweepmap-motor sweeping the simulated stepper in mode 7 (private
// network namespace). Prints figures; asserts nothing.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace sweepmap {

struct DevicesBenchOptions {
  std::string bin_dir;        // sweepmap, sweepmap-lidar, -odometry ("" = skip the processes)
  double process_s = 10.0;    // how long each process is measured
  double decode_min_s = 1.0;  // each decoder runs at least this long
};

// One on-board process measured at its full rates.
struct ProcessLoad {
  std::string name;  // sweepmap-lidar
  std::string what;  // its devices and rates
  double cpu_share;  // CPU seconds / wall seconds (1 = one core)
  int64_t rss_kib;   // peak resident set (VmHWM)
};

// `loads` (if given) receives the processes measured, for the on-board summary.
int benchDevices(const DevicesBenchOptions& options, std::ostream& out,
                 std::vector<ProcessLoad>* loads = nullptr);

}  // namespace sweepmap
