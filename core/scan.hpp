// A raw 2D lidar scan as the driver delivers it, independent of any transport.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sweepmap {

struct Scan2D {
  int64_t utime = 0;           // time of the first ray [us]
  int64_t seq = 0;             // device scan counter
  double angle_min_rad = 0.0;  // angle of ray 0 in the lidar frame, from Z_L toward Y_L
  double angle_increment_rad = 0.0;
  int64_t time_increment_ns = 0;  // time between consecutive rays
  double range_min_m = 0.0;
  double range_max_m = 0.0;
  // Range of each ray [m]; 0 means "no return". Everything else outside
  // [range_min_m, range_max_m] is invalid.
  std::vector<float> ranges_m;

  double rayAngle(size_t i) const { return angle_min_rad + angle_increment_rad * double(i); }
  int64_t rayUtime(size_t i) const {
    return utime + (time_increment_ns * static_cast<int64_t>(i)) / 1000;
  }
};

// Checks a scan from outside: length (when expected_beams > 0), finite header and ranges,
// ranges 0 (no return) or within the sensor's limits (with headroom for noise).
// Returns an empty string when valid, else the reason.
std::string validateScan(const Scan2D& scan, int expected_beams);

}  // namespace sweepmap
