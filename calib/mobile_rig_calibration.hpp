// Rig B's joint calibration (issue 23): every parameter a drive makes observable, from the
// gyro against the wheels and the lidar's passes over the same surfaces.
//
// What determines what, and the stated order:
//   1. The wheels against the gyro (calib/wheel_gyro_calibration.hpp): each radius over the
//      track, k_L = r_L / T and k_R = r_R / T, and the gyro's bias (from the stops). No lidar.
//      The wheels become (k_L T, k_R T, T) with T at the rig file's track.
//   2. The lidar: the common scale e of (r_L, r_R, T) is the distance driven, the one wheel
//      error no turn rate shows; it moves the world points of the passes, as the mounting
//      (gamma, beta, alpha), its lever arm and the lidar-to-odometry time offset do. These
//      are one least squares (calib/overlap_alignment.hpp) on the odometry re-run with the
//      corrected wheels, its track linearised in e by re-running it with the scale moved: each
//      point against the plane of its patch (both passes' points, the plane eliminated), each
//      sigma the larger of that solve's and point-to-plane's at the same solution.
//      Iterated twice (the odometry re-run at the new scale).
//   3. A parameter whose sigma exceeds its observability bound is reported unobservable,
//      held at nominal, and the least squares solved again without it. (Judged on the patches'
//      information, before the sigmas are widened: a kept parameter's reported sigma may exceed
//      its bound on a weak drive.) Chosen in the first iteration; the second, whose odometry
//      differs only by the scale, solves over the same choice.
// The covariance: step 1's and step 2's are independent data (block diagonal), carried to the
// reported parameters by the Jacobian of r = k T0 (1 + e), T = T0 (1 + e).
// Then the room: its walls, floor and ceiling fitted in the calibrated cloud (RANSAC, one
// thread: calib/room_planes.hpp) give its length, width and height (measures room.*_m).
// Transport-free: the odometry is re-run through a callback.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "calib/mounting_calibration.hpp"
#include "calib/rig_calibration.hpp"
#include "calib/wheel_gyro_calibration.hpp"
#include "calib/world_assembly.hpp"

namespace sweepmap {

struct MobileWheelParameters {
  double radius_left_m = 0.0325;
  double radius_right_m = 0.0325;
  double wheel_distance_m = 0.2;
};

// The odometry re-run over the drive's wheel and IMU readings with these wheels.
struct MobileOdometryRun {
  PoseTrack track;
  double gyro_bias_rad_s = 0.0;        // the EKF's estimate at the end of the drive
  double gyro_bias_sigma_rad_s = 0.0;  // its sigma
};
using MobileOdometryReplay = std::function<MobileOdometryRun(const MobileWheelParameters&)>;

struct MobileRigCalibrationInput {
  std::vector<Scan2D> scans;
  LidarMounting nominal;  // the rig file's mounting (the start)
  // The rig file's lidar.time_offset_s, by which `scans` are already on the odometry's clock:
  // the estimate is this plus the drive's remaining offset.
  double time_offset_s = 0.0;
  double gyro_bias_rad_s = 0.0;   // the rig file's odometry.gyro_bias_rad_s (reported beside)
  MobileWheelParameters wheels;   // the rig file's wheels (the start)
  MobileOdometryReplay odometry;  // required
  // The drive's raw encoder and gyro readings (step 1); empty: the wheels and the gyro bias
  // are left nominal and reported unobservable.
  std::vector<WheelReading> wheel_readings;
  std::vector<GyroReading> gyro_readings;
  WheelGyroOptions wheel_gyro;  // ticks_per_revolution: the rig file's
  MountingCalibrationOptions options;
  std::map<std::string, double> truth;  // simulated logs: rig-file key -> true value
  // The room's true length, width and height (the longer and shorter wall spacing, floor to
  // ceiling; simulated logs: the scene's), to compare the calibrated cloud's with.
  std::optional<Eigen::Vector3d> room_truth_m;
  std::function<void(double)> progress;  // fraction done (may be empty)
};

// Keys (rig-file keys where the rig file has one): mounting.gamma_rad, beta_rad, alpha_rad,
// mounting.x_m, y_m, z_m, odometry.wheel_radius_m (left), odometry.wheel_radius_right_m,
// odometry.wheel_distance_m, odometry.gyro_bias_rad_s, lidar.time_offset_s (the lidar's
// stamps minus the odometry's clock).
RigCalibration calibrateMobileRig(const MobileRigCalibrationInput& input);

}  // namespace sweepmap
