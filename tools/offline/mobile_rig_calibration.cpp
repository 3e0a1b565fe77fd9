// Rig B's whole calibration from logs: see tools/offline/mobile_rig_calibration.hpp.
#include "tools/offline/mobile_rig_calibration.hpp"

#include <algorithm>

#include "calib/mobile_rig_calibration.hpp"
#include "core/heap_reuse.hpp"
#include "core/progress.hpp"
#include "rigs/rig_file.hpp"
#include "tools/offline/mobile_log.hpp"

namespace sweepmap {
namespace {

// The simulator's truth under the result's keys.
std::map<std::string, double> truthOf(const MobileLog& log) {
  std::map<std::string, double> t;
  if (log.truth_mounting) {
    t["mounting.gamma_rad"] = log.truth_mounting->gamma_true_rad;
    t["mounting.beta_rad"] = log.truth_mounting->beta_true_rad;
    t["mounting.alpha_rad"] = log.truth_mounting->alpha_true_rad;
  }
  if (log.truth_rig) {
    const truth_mobile_rig_t& r = *log.truth_rig;
    t["mounting.x_m"] = r.t_BL_true_m[0];
    t["mounting.y_m"] = r.t_BL_true_m[1];
    t["mounting.z_m"] = r.t_BL_true_m[2];
    t["odometry.wheel_radius_m"] = r.wheel_radius_left_m;
    t["odometry.wheel_radius_right_m"] = r.wheel_radius_right_m;
    t["odometry.wheel_distance_m"] = r.wheel_distance_m;
    t["odometry.gyro_bias_rad_s"] = r.gyro_bias_z_rad_s;
    t["lidar.time_offset_s"] = r.lidar_time_offset_s;
  }
  return t;
}

// A simulated drive's room, from its TRUTH_MOUNTING (the scene it was simulated in, whichever
// --scene gave), as (length, width, height): the longer and the shorter wall spacing, floor to
// ceiling.
Eigen::Vector3d simulatedRoom(const truth_mounting_t& m) {
  return {std::max(m.room_size_m[0], m.room_size_m[1]),
          std::min(m.room_size_m[0], m.room_size_m[1]), m.room_size_m[2]};
}

}  // namespace

RigCalibration runMobileRigCalibration(const MobileRigCalibRequest& request) {
  keepFreedMemoryForReuse();  // the joint solve's rounds: core/heap_reuse.hpp
  const MobileLidarConfig rig = loadMobileLidarConfig(resolveRigFile(request.rig), request.sets);
  ProgressOptions po;
  po.enabled = request.progress;
  Progress progress("calib rig", po);
  progress.stage("reading the log");
  const MobileLog log = loadMobileLog(request.logs.at(0), rig);
  MobileRigCalibrationInput in;
  in.scans = log.scans;
  in.nominal = rig.mounting.toMounting();
  in.time_offset_s = rig.assembler.lidar_time_offset_s;
  in.gyro_bias_rad_s = rig.odometry.ekf.initial_bias_rad_s;
  in.wheels.radius_left_m = rig.odometry.wheel_radius_m;
  in.wheels.radius_right_m = rig.odometry.rightWheelRadius();
  in.wheels.wheel_distance_m = rig.odometry.ekf.wheel_distance_m;
  in.truth = truthOf(log);
  if (log.truth_mounting) in.room_truth_m = simulatedRoom(*log.truth_mounting);
  const OdometryReadings readings = loadOdometryReadings(request.logs.at(0));
  in.wheel_readings = readings.wheels;
  in.gyro_readings = readings.gyro;
  in.wheel_gyro.ticks_per_revolution = rig.odometry.ticks_per_revolution;
  in.odometry = [&](const MobileWheelParameters& w) {
    MobileLidarConfig r = rig;
    r.odometry.wheel_radius_m = w.radius_left_m;
    r.odometry.wheel_radius_right_m = w.radius_right_m;
    r.odometry.ekf.wheel_distance_m = w.wheel_distance_m;
    const MobileLog replayed = loadMobileLog(request.logs.at(0), r);
    return MobileOdometryRun{replayed.ekf, replayed.ekf_gyro_bias_rad_s,
                             replayed.ekf_gyro_bias_sigma_rad_s};
  };
  progress.stage("joint least squares");
  in.progress = [&progress](double f) { progress.update(f); };
  RigCalibration result = calibrateMobileRig(in);
  progress.finish();
  if (log.log_error) result.warnings.push_back(request.logs[0] + ": " + log.error);
  if (request.logs.size() > 1)
    result.warnings.push_back("rig B calibrates from one drive; only " + request.logs[0] +
                              " was used");
  return result;
}

}  // namespace sweepmap
