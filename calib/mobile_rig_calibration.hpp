// Rig B's joint calibration (issue 23): every parameter a drive makes observable, from the
// lidar's two passes over the same surfaces and the odometry's own readings.
//
// The physics couples the lidar's mounting (gamma, beta, alpha), its lever arm, the
// lidar-to-odometry time offset and the wheels (radii, track width): all move the world
// points of the two passes, through the mounting directly and through the track the
// odometry integrates. They are estimated in one least squares (calib/overlap_alignment.hpp)
// whose track is linearised in the wheel parameters by re-running the odometry with each
// perturbed. The gyro bias is the odometry EKF's own state, estimated against the wheels and
// the IMU's yaw, and is read from it. Stated order, iterated twice:
//   1. odometry at the current wheel parameters (and its sensitivities to them);
//   2. one joint least squares of the mounting, lever arm, time offset and wheel changes;
//   3. a parameter whose sigma exceeds its observability bound is reported unobservable,
//      held at nominal, and the least squares solved again without it.
// Transport-free: the odometry is re-run through a callback.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "calib/mounting_calibration.hpp"
#include "calib/rig_calibration.hpp"
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
  LidarMounting nominal;          // the rig file's mounting (the start)
  MobileWheelParameters wheels;   // the rig file's wheels (the start)
  MobileOdometryReplay odometry;  // required
  MountingCalibrationOptions options;
  std::map<std::string, double> truth;   // simulated logs: rig-file key -> true value
  std::function<void(double)> progress;  // fraction done (may be empty)
};

// Keys (rig-file keys where the rig file has one): mounting.gamma_rad, beta_rad, alpha_rad,
// mounting.x_m, y_m, z_m, odometry.wheel_radius_m (left), odometry.wheel_radius_right_m,
// odometry.wheel_distance_m, odometry.gyro_bias_rad_s, lidar.time_offset_s (the lidar's
// stamps minus the odometry's clock).
RigCalibration calibrateMobileRig(const MobileRigCalibrationInput& input);

}  // namespace sweepmap
