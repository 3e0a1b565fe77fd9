// Rig kind `mobile_lidar` (rig B, Miao 2022): a 2D lidar on a moving differential-drive
// base with wheel encoders and an IMU. Odometry, the lidar's mounting, the world-frame
// assembler and the mapper, from one strictly loaded YAML file (config/rig_b.yaml).
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/mounting.hpp"
#include "core/rig_components.hpp"
#include "core/scan.hpp"
#include "odometry/odometry_config.hpp"
#include "sim/mobile.hpp"

namespace sweepmap {

struct MountingConfig {
  double nominal_roll_deg = 0.0;   // how the lidar is meant to sit (e.g. pitch 90: horizontal,
  double nominal_pitch_deg = 0.0;  // sector middle looking forward)
  double nominal_yaw_deg = 0.0;
  double gamma_rad = 0.0;  // mounting error about x (calibrated)
  double beta_rad = 0.0;   // about y
  double alpha_rad = 0.0;  // about z
  double x_m = 0.0;        // lidar centre in the body frame (l1, 0, h)
  double y_m = 0.0;
  double z_m = 0.0;
  // A calibration YAML (relative to the rig file; "" = none) whose mounting.{gamma,beta,
  // alpha}_rad replace the three values above (core/calibration_file.hpp).
  std::string calibration_file;
  void declare(ConfigSchema& s, const std::string& prefix);
  LidarMounting toMounting() const;
};

struct WorldAssemblerConfig {
  std::string pose_channel = "ODOMETRY_POSE";  // or WHEEL_ODOMETRY
  int beam_count = 0;                          // expected rays per scan; 0 = any
  double max_pose_wait_s =
      2.0;  // a scan whose pose does not come within this is assembled with what is there
  // The lidar's stamps minus the odometry's clock (rig key lidar.time_offset_s; sweepmap calib
  // rig measures it): a ray stamped t is placed with the pose at t - lidar_time_offset_s.
  double lidar_time_offset_s = 0.0;
  void declare(ConfigSchema& s, const std::string& prefix);
  int64_t lidarTimeOffsetUs() const {
    return static_cast<int64_t>(std::llround(lidar_time_offset_s * 1e6));
  }
  // Puts a scan stamped by the lidar on the odometry's clock.
  void toOdometryClock(Scan2D* scan) const { scan->utime -= lidarTimeOffsetUs(); }
};

struct MobileLidarConfig {
  std::string rig = "mobile_lidar";  // the kind, checked on load
  // sweepmap calib rig's file (relative to the rig file; "" = none): its keys replace the rig
  // file's (rigs/rig_kind.hpp applyRigCalibration), before mounting.calibration_file.
  std::string calibration_file;
  LidarConfig lidar;  // the lidar as its driver sees it (360° scanners: a uniform ray grid)
  OdometryConfig odometry;
  // The odometry process's devices (core/device_uri.hpp); `sweepmap-odometry --imu-device /
  // --wheels-device` override. sim: the simulated car's (sim.* below).
  std::string imu_device = "sim";     // sim | hi219:///dev/ttyUSB1[?baud=N]
  std::string wheels_device = "sim";  // sim | wheelboard:///dev/ttyACM0[?baud=N]
  MountingConfig mounting;
  WorldAssemblerConfig assembler;
  MapperConfig mapper;
  NetworkConfig network;  // every live process: its receive queue and datagram reassembly
  SimMobileConfig sim;    // `sweepmap sim` only: the simulated car's truth and noise
  // The car as built: the rig file's wheels and lidar position before its calibration_file.
  // The simulated car is these plus its sim.* errors, so a calibrated rig file simulates the
  // same car as the file it calibrated. Unset (a config not loaded from a file): the values
  // above.
  struct Build {
    double wheel_radius_m, wheel_radius_right_m, wheel_distance_m;
    Eigen::Vector3d t_BL_m;
  };
  std::optional<Build> as_built;
  Build build() const {
    return as_built.value_or(Build{odometry.wheel_radius_m, odometry.rightWheelRadius(),
                                   odometry.ekf.wheel_distance_m, mounting.toMounting().t_BL_m});
  }
  void declare(ConfigSchema& s);
};

// Loads a rig file strictly (its `rig` key must say mobile_lidar), then applies `key=value`
// overrides; a rig calibration file the rig names replaces its keys, then a mounting
// calibration file the rig names replaces the mounting angles.
// Throws ConfigError naming the file and the key.
MobileLidarConfig loadMobileLidarConfig(const std::string& path,
                                        const std::vector<std::string>& overrides = {});

}  // namespace sweepmap
