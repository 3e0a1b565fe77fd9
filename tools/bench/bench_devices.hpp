// Real-device part of `sweepmap bench`: each protocol decoder's throughput (the driver's
// session: decode + scan assembly + timing) against the device's own data rate, and the CPU
// share of the real sweepmap-lidar process driving an emulated UST-10LX at 40 Hz over
// loopback TCP, and of sweepmap-odometry reading the emulated HI219 (400 Hz) and wheel board
// (100 Hz) on ptys (private network namespace). Prints figures; asserts nothing.
#pragma once

#include <ostream>
#include <string>

namespace sweepmap {

struct DevicesBenchOptions {
  std::string bin_dir;        // sweepmap, sweepmap-lidar, -odometry ("" = skip the processes)
  double process_s = 10.0;    // how long each process is measured
  double decode_min_s = 1.0;  // each decoder runs at least this long
};

int benchDevices(const DevicesBenchOptions& options, std::ostream& out);

}  // namespace sweepmap
