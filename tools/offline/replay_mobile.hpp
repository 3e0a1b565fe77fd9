// Offline replay of a rig-B log (wheel ticks, IMU, lidar scans): the odometry process,
// the world-frame assembler and the mapper in one thread, in log order.
#pragma once

#include <string>

#include "rigs/mobile_lidar.hpp"

namespace sweepmap {

struct MobileReplayResult {
  int64_t events = 0;
  int64_t scans = 0;
  int64_t points = 0;
  bool log_error = false;
  std::string error;
};

// Writes DIR/map.bt, DIR/cloud.pcd (all world points), DIR/derived.lcmlog,
// DIR/summary.json and DIR/top_view.png (cloud with the EKF and wheel-odometry paths).
MobileReplayResult replayMobileLog(const std::string& log_path, const MobileLidarConfig& rig,
                                   const std::string& out_dir, bool plots = true,
                                   bool progress = false);

}  // namespace sweepmap
