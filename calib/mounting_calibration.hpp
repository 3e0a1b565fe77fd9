// Calibration of a 2D lidar's 3-axis mounting error on a moving base (rig B, Miao 2022
// section 4.2, Eq. 15-17): the car drives a path that shows the same surfaces twice (a
// circle: the vertical scan plane sweeps every direction once with each side of the
// scan), and the mounting error (gamma about body x, beta about y, alpha about z) is the
// one under which the two passes agree.
//
// Two methods on the same data:
//  - kPaperPoints (the paper's): corresponding points of the two passes, found
//    automatically (corners and edges of the calibration target, not hand picks), and
//    Levenberg-Marquardt on the sum of their squared distances (Eq. 15-17);
//  - kPointToPlane (ours): Ceres over all overlapping points of the two passes, each
//    point against the local plane the other pass sees there, with a robust loss;
//    optionally the lidar-to-odometry time offset as a fourth parameter.
//
// Transport-free and PCL/Ceres-free in this header.
#pragma once

#include <string>
#include <vector>

#include "calib/world_assembly.hpp"
#include "core/scan.hpp"

namespace sweepmap {

enum class MountingMethod { kPaperPoints, kPointToPlane };

const char* mountingMethodName(MountingMethod m);  // "paper_points", "point_to_plane"

struct MountingCalibrationOptions {
  MountingMethod method = MountingMethod::kPointToPlane;
  // Two observations of one place belong to different passes when their scans are at
  // least this far apart in time.
  double min_pass_gap_s = 5.0;
  bool estimate_time_offset = false;  // kPointToPlane only: pose time = ray time + offset
  double max_time_offset_s = 0.1;     // bound of the time offset
};

struct MountingCalibrationResult {
  bool ok = false;
  std::string reason;  // why not ok (too few correspondences, no overlap, ...)
  MountingMethod method = MountingMethod::kPointToPlane;
  double gamma_rad = 0.0, beta_rad = 0.0, alpha_rad = 0.0;
  double time_offset_s = 0.0;  // 0 unless estimated
  // RMS of the method's residuals [m] at the initial mounting and at the estimate.
  double residual_before_m = 0.0, residual_after_m = 0.0;
  int correspondences = 0;  // point pairs (paper) or point-plane pairs (ours) used
  int iterations = 0;
};

// `scans`: the lidar scans of the drive (Scan2D::utime = first ray); `track`: the car's
// planar poses (the odometry's), covering the scans; `initial`: the nominal rotation, the
// lidar's position and the initial guess of (gamma, beta, alpha), usually zeros.
// Deterministic: the same input gives the same result.
MountingCalibrationResult calibrateMounting(const std::vector<Scan2D>& scans, const PoseTrack& track,
                                            const LidarMounting& initial,
                                            const MountingCalibrationOptions& options);

}  // namespace sweepmap
