// Assembly of one 3D sweep of rig A from the 2D scans of its lidar window:
// C_O' by Eq. 4-7, the plate's beta, phi_offset = alpha - beta (Eq. 10) and C_O (Eq. 8-9).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "calib/plate.hpp"
#include "calib/rotating_geometry.hpp"
#include "core/scan.hpp"
#include "rigs/rotating_lidar.hpp"

namespace sweepmap {

struct SweepWindow {
  int64_t sweep_id = 0;
  int mode = 0;
  int64_t start_utime = 0;  // scans whose first ray is in [start, end) belong to the sweep
  int64_t end_utime = 0;
  double omega_rad_s = 0.0;    // constant shaft speed over the window
  bool accel_overlap = false;  // the motor's timing says a ramp overlapped the window
};

struct AssembledSweep {
  SweepWindow window;
  int scans = 0;
  int64_t first_ray_utime = 0;             // phi_motor = 0 here: the instant frame O' is defined
  std::vector<Eigen::Vector3f> points_Op;  // C_O'
  std::vector<Eigen::Vector3f> points;     // C_O when corrected, else C_O'
  // Empty when a scan of the window has no intensities (a lidar that measures none), else
  // one per point of points_Op and points, in their order: the ray's intensity (device units).
  std::vector<float> intensities;
  std::vector<PlateRay> plate_rays;  // rays meeting the plate plane in the region
  PlateEstimate plate;
  PlateCheck plate_check;  // the estimate against the plate's shape
  double alpha_rad = 0.0;
  double phi_offset_rad = 0.0;  // applied rotation (0 when not corrected)
  bool corrected = false;
  std::string reason;  // why not corrected
  // Scans of the window that never reached the assembler (a gap in their seq; set by
  // processes/assembler_node, 0 here): the sweep is incomplete.
  int missing_scans = 0;
};

// The raw observation of one valid ray of a sweep: the shaft angle phi_motor at the ray's
// own time (Eq. 7 by time, per-ray timing), the range and the ray's angle theta in the scan
// (Eq. 4). Enough to place the point with any t_L^O' (calib/axis_offset_lidar.hpp).
struct SweepRay {
  double phi_rad = 0.0;
  double range_m = 0.0;
  double theta_rad = 0.0;
  float intensity = 0.0f;  // the device's reading; 0 when its scan has no intensities
  // Where the ray was measured (forEachSweepRay): its scan's index in the window and its index
  // in that scan; -1 when not known (rays made by hand).
  int32_t scan = -1;
  int32_t beam = -1;
};

// Calls f(ray) for every valid ray of `scans` (a window's scans in time order, the first
// scan's first ray at phi = 0), in the order assembleSweep makes points_Op: rays with range
// 0 or outside [range_min, range_max] of their scan are skipped.
template <class F>
void forEachSweepRay(const std::vector<Scan2D>& scans, double omega_rad_s, F&& f) {
  if (scans.empty()) return;
  const int64_t first_ray_utime = scans.front().utime;
  for (size_t k = 0; k < scans.size(); ++k) {
    const Scan2D& scan = scans[k];
    const double t_ray_s = 1e-9 * static_cast<double>(scan.time_increment_ns);
    const double phi0 = rotating::motorAngleFromTime(scan.utime, first_ray_utime, omega_rad_s);
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      if (!scan.validRange(i)) continue;
      const double r = scan.ranges_m[i];
      // Per-ray time: the shaft keeps turning while the mirror sweeps the scan.
      const float intensity = i < scan.intensities.size() ? scan.intensities[i] : 0.0f;
      f(SweepRay{phi0 + omega_rad_s * t_ray_s * static_cast<double>(i), r, scan.rayAngle(i),
                 intensity, static_cast<int32_t>(k), static_cast<int32_t>(i)});
    }
  }
}

// `scans` must be the valid scans of the window in time order. Rays with range 0 or
// outside [range_min, range_max] of their scan are skipped.
AssembledSweep assembleSweep(const std::vector<Scan2D>& scans, const SweepWindow& window,
                             const RotatingLidarConfig& rig);

// The attitude correction alone (Eq. 8-10): beta by plate.beta_method, the shape check,
// phi_offset = alpha - beta and C_O, from points_Op and plate_rays. assembleSweep calls it;
// tools re-run it to compare methods or alphas without re-assembling.
void correctSweep(const RotatingLidarConfig& rig, AssembledSweep* sweep);

// Takes a correction back (C_O' published) for `reason`: e.g. scans of the window were lost,
// so the plate may be incompletely seen and its beta moved.
void uncorrectSweep(const std::string& reason, AssembledSweep* sweep);

}  // namespace sweepmap
