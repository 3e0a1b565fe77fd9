#include "rigs/mobile_lidar.hpp"

#include <cmath>
#include <filesystem>

#include "core/calibration_file.hpp"
#include "core/device_uri.hpp"
#include "rigs/rig_kind.hpp"

namespace sweepmap {

void MountingConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "nominal_roll_deg", &nominal_roll_deg, "deg", "nominal lidar roll on the body");
  s.add(p + "nominal_pitch_deg", &nominal_pitch_deg, "deg",
        "nominal lidar pitch (90: horizontal scan plane, sector middle forward)");
  s.add(p + "nominal_yaw_deg", &nominal_yaw_deg, "deg", "nominal lidar yaw");
  s.add(p + "gamma_rad", &gamma_rad, "rad", "mounting error about body x (calibrated)");
  s.add(p + "beta_rad", &beta_rad, "rad", "mounting error about body y (calibrated)");
  s.add(p + "alpha_rad", &alpha_rad, "rad", "mounting error about body z (calibrated)");
  s.add(p + "x_m", &x_m, "m", "lidar centre along body x (l1)");
  s.add(p + "y_m", &y_m, "m", "lidar centre along body y");
  s.add(p + "z_m", &z_m, "m", "lidar centre above the body plane (h)");
  s.add(p + "calibration_file", &calibration_file, "",
        "calibration YAML (relative to the rig file) whose mounting.gamma/beta/alpha_rad replace "
        "gamma/beta/alpha_rad; \"\" = none (sweepmap calib mounting writes it)");
}

LidarMounting MountingConfig::toMounting() const {
  LidarMounting m;
  m.nominal_rpy_rad =
      Eigen::Vector3d(nominal_roll_deg, nominal_pitch_deg, nominal_yaw_deg) * kDegToRad;
  m.gamma_rad = gamma_rad;
  m.beta_rad = beta_rad;
  m.alpha_rad = alpha_rad;
  m.t_BL_m = Eigen::Vector3d(x_m, y_m, z_m);
  return m;
}

void WorldAssemblerConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "pose_channel", &pose_channel, "",
        "pose stream: ODOMETRY_POSE (EKF) or WHEEL_ODOMETRY");
  s.add(p + "beam_count", &beam_count, "", "expected rays per scan (0: any)");
  s.add(p + "max_pose_wait_s", &max_pose_wait_s, "s",
        "assemble a scan with the poses there are after this long");
}

void MobileLidarConfig::declare(ConfigSchema& s) {
  s.add("rig", &rig, "", "rig kind: mobile_lidar (a 2D lidar on a moving base, Miao 2022)");
  s.add("calibration_file", &calibration_file, "",
        "calibration YAML (relative to the rig file) of sweepmap calib rig, whose rig-file keys "
        "replace these values (before mounting.calibration_file); empty: none");
  lidar.declare(s, "lidar.");
  s.add("lidar.time_offset_s", &assembler.lidar_time_offset_s, "s",
        "the lidar's stamps minus the odometry's clock: a ray stamped t is placed with the pose "
        "at t minus this (sweepmap calib rig measures it)");
  odometry.declare(s, "odometry.");
  s.add("imu.device", &imu_device, "",
        "the IMU sweepmap-odometry opens: sim | hi219:///dev/PORT[?baud=N] (HiPNUC HI219)");
  s.add("wheels.device", &wheels_device, "",
        "the wheel board sweepmap-odometry opens: sim | wheelboard:///dev/PORT[?baud=N] "
        "(drivers/protocols/wheelboard.hpp)");
  mounting.declare(s, "mounting.");
  assembler.declare(s, "assembler.");
  mapper.declare(s, "mapper.");
  s.add("mapper.batch_s", &mapper.batch_s, "s",
        "scans whose time falls in the same window of this length are inserted as one batch "
        "(one update of the tree's inner nodes and one MAP_STATS; the map is the same); 0: "
        "every scan on its own");
  network.declare(s, "network.");
  sim.declare(s, "sim.");
}

namespace {

// The rig file's range checks (ConfigError naming `path` and the key).
void checkMobileLidarConfig(const std::string& path, const MobileLidarConfig& c) {
  c.lidar.validate(path, "lidar.");
  const auto device = [&](const std::string& key, const std::string& value, DeviceProtocol p) {
    try {
      parseDeviceUriFor(value, {p});
    } catch (const std::invalid_argument& e) {
      throw ConfigError(path + ": key '" + key + "': " + e.what());
    }
  };
  device("imu.device", c.imu_device, DeviceProtocol::kHi219);
  device("wheels.device", c.wheels_device, DeviceProtocol::kWheelBoard);
  const auto positive = [&](double v, const char* key) {
    if (!(v > 0)) throw ConfigError(path + ": key '" + key + "' must be > 0");
  };
  positive(c.odometry.wheel_radius_m, "odometry.wheel_radius_m");
  positive(c.odometry.ticks_per_revolution, "odometry.ticks_per_revolution");
  positive(c.odometry.ekf.wheel_distance_m, "odometry.wheel_distance_m");
  if (!(c.odometry.wheel_radius_right_m >= 0)) {
    throw ConfigError(path + ": key 'odometry.wheel_radius_right_m' must be >= 0 (0: the left's)");
  }
  if (!(std::abs(c.odometry.ekf.initial_bias_rad_s) <= 1.0)) {
    throw ConfigError(path + ": key 'odometry.gyro_bias_rad_s' must be within +-1 rad/s");
  }
  if (!(std::abs(c.assembler.lidar_time_offset_s) <= 1.0)) {
    throw ConfigError(path + ": key 'lidar.time_offset_s' must be within +-1 s");
  }
  if (!(c.mapper.batch_s >= 0.0 && c.mapper.batch_s <= 3600.0)) {
    throw ConfigError(path + ": key 'mapper.batch_s' must be in [0, 3600]");
  }
  c.mapper.validateBounds(path, "mapper.");
  c.network.validate(path, "network.");
  if (c.assembler.pose_channel != "ODOMETRY_POSE" && c.assembler.pose_channel != "WHEEL_ODOMETRY") {
    throw ConfigError(path +
                      ": key 'assembler.pose_channel' must be ODOMETRY_POSE or WHEEL_ODOMETRY");
  }
}

}  // namespace

MobileLidarConfig loadMobileLidarConfig(const std::string& path,
                                        const std::vector<std::string>& overrides) {
  MobileLidarConfig c;
  ConfigSchema s;
  loadRigSchema(path, overrides, "mobile_lidar", &c, &s);
  c.as_built = c.build();
  CalibratedKeys calibrated;
  if (!c.calibration_file.empty())
    calibrated = applyRigCalibration(path, c.calibration_file, overrides, &s);
  checkCalibratedRig(path, calibrated, [&] { checkMobileLidarConfig(path, c); });
  if (!c.mounting.calibration_file.empty()) {
    const MountingCalibration m = loadFileBesideRig(
        path, "mounting.calibration_file", c.mounting.calibration_file, loadMountingCalibration);
    c.mounting.gamma_rad = m.gamma_rad;
    c.mounting.beta_rad = m.beta_rad;
    c.mounting.alpha_rad = m.alpha_rad;
  }
  return c;
}

}  // namespace sweepmap
