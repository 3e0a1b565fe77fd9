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
  // The device's own stamp of the scan, raw (SCIP: 24-bit millisecond counter); -1 = none.
  int64_t device_stamp = -1;
  // Empty, or one per ray: the device's intensity / reflectance reading (device units).
  std::vector<float> intensities;
  // Empty: ray i is at angle_min_rad + i * angle_increment_rad. Else one per ray: the angle
  // the device measured for that ray (devices whose samples are not on a fixed grid).
  std::vector<float> angles_rad;

  // Whether ray i holds a range (not 0, not NaN, within [range_min_m, range_max_m]).
  bool validRange(size_t i) const {
    const double r = ranges_m[i];
    return r != 0.0 && r >= range_min_m && r <= range_max_m;
  }
  double rayAngle(size_t i) const {
    return angles_rad.empty() ? angle_min_rad + angle_increment_rad * double(i)
                              : double(angles_rad[i]);
  }
  int64_t rayUtime(size_t i) const {
    return utime + (time_increment_ns * static_cast<int64_t>(i)) / 1000;
  }
};

// Checks a scan from outside: length (when expected_beams > 0 and the scan is on a grid: a
// scan with its own angles, one turn of a 360° lidar, holds as many samples as the turn had),
// finite header and ranges,
// ranges 0 (no return) or within the sensor's limits (with headroom for noise).
// Returns an empty string when valid, else the reason.
std::string validateScan(const Scan2D& scan, int expected_beams);

}  // namespace sweepmap
