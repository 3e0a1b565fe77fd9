// Configuration of rig B's odometry (keys odometry.* of a mobile_lidar rig file): the
// wheels' geometry and the EKF's noise model.
#pragma once

#include <string>

#include "core/config.hpp"
#include "odometry/ekf.hpp"

namespace sweepmap {

struct OdometryConfig {
  double wheel_radius_m = 0.077;
  // The right wheel's radius when it differs from the left's (wheel_radius_m); 0: the same.
  // Rig key odometry.wheel_radius_right_m; sweepmap calib rig measures it.
  double wheel_radius_right_m = 0.0;
  // The right wheel's radius: wheel_radius_right_m, or wheel_radius_m when that is 0.
  double rightWheelRadius() const {
    return wheel_radius_right_m > 0 ? wheel_radius_right_m : wheel_radius_m;
  }
  double ticks_per_revolution = 4000.0;  // BreezySLAM's Mines rover: 180 deg per 2000 ticks
  bool use_imu = true;
  EkfConfig ekf;
  void declare(ConfigSchema& s, const std::string& prefix);
};

}  // namespace sweepmap
