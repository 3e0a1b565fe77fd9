// Rig B's wheels against its gyro (issue 23): the gyro measures the turn rate whatever the
// wheels are, the encoders measure it as (r_R dphi_R - r_L dphi_L) / track. Over short
// windows of the drive,
//   dtheta_gyro = k_R dphi_R - k_L dphi_L + b dt,   k = wheel radius / track,
// is linear in (k_L, k_R, b): straights (dphi_R ~ dphi_L) fix the ratio of the radii, turns
// both ways fix each radius against the track, and stops (dphi = 0) fix the gyro's bias.
// The common scale of the radii and the track is not determined by any turn rate (scaling
// all three leaves every turn rate as it was): it is the distance driven, which the lidar
// measures against the room (calib/mobile_rig_calibration.hpp).
//
// Windows where a wheel slipped or the gyro has a gap disagree by far more than the noise
// and are trimmed (iteratively, beyond kTrimSigma of the inliers' scatter); the sigma
// comes from the inliers' own scatter, so it grows when the model does not explain them.
// The gyro's scale factor is taken as exact (a turn-table check, not a drive, calibrates it).
// Transport-free.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace sweepmap {

struct WheelReading {
  int64_t utime;
  int64_t left, right;  // cumulative encoder counts
};
struct GyroReading {
  int64_t utime;
  double z_rad_s;  // turn rate about the body's z (up)
};

struct WheelGyroOptions {
  double ticks_per_revolution = 2000;
  double window_s = 0.5;         // each row's span (whole wheel readings)
  double max_gyro_gap_s = 0.05;  // a window with a longer gap between gyro samples is skipped
  double trim_sigma = 4.0;       // rows beyond this many sigma are dropped (slip)
  int trim_iterations = 6;
  double rest_rad = 1e-9;  // both wheels turned less than this: the car stood still
  // k_L and k_R count as determined when each one's sigma is below this fraction of it. On a
  // drive whose wheels keep one ratio (a circle) the windows' rows are nearly parallel, and
  // least squares with the encoders' noise in the rows shrinks both k towards 0 with a small
  // absolute sigma (regression dilution): relative to k, that sigma is large.
  double max_relative_sigma = 0.01;
};

struct WheelGyroResult {
  bool ok = false;
  std::string reason;
  // (k_left, k_right, bias): radius / track of each wheel [1] and the gyro's z bias [rad/s].
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  int rows = 0;          // windows used
  int rest_rows = 0;     // of them, standing still
  int trimmed = 0;       // windows dropped as outliers (slip)
  double sigma_rad = 0;  // scatter of one moving window's residual
};

WheelGyroResult calibrateWheelsAgainstGyro(const std::vector<WheelReading>& wheels,
                                           const std::vector<GyroReading>& gyro,
                                           const WheelGyroOptions& options);

}  // namespace sweepmap
