// Configuration of rig B's odometry (keys odometry.* of a mobile_lidar rig file): the
// wheels' geometry and the EKF's noise model.
#pragma once

#include <string>

#include "core/config.hpp"
#include "odometry/ekf.hpp"

namespace sweepmap {

struct OdometryConfig {
  double wheel_radius_m = 0.077;
  double ticks_per_revolution = 4000.0;  // BreezySLAM's Mines rover: 180 deg per 2000 ticks
  bool use_imu = true;
  EkfConfig ekf;
  void declare(ConfigSchema& s, const std::string& prefix);
};

}  // namespace sweepmap
