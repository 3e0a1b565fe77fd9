// Rig B's whole calibration from logs (the `calib rig` command's mobile_lidar part): reads
// the drive and its raw encoder and gyro readings, re-runs its odometry with the wheels the
// joint least squares asks for (calib/mobile_rig_calibration.hpp), and fills the truth from a
// simulated log (the room's from its TRUTH_MOUNTING: the scene it was simulated in).
#pragma once

#include <string>
#include <vector>

#include "calib/rig_calibration.hpp"

namespace sweepmap {

struct MobileRigCalibRequest {
  std::vector<std::string> logs;  // one drive (the first is used; more: a warning)
  std::string rig;                // rig file or name (mobile_lidar)
  std::vector<std::string> sets;  // rig overrides, key=value
  bool progress = true;           // on a terminal, unless --json
};

// Throws ConfigError for a bad rig and LogError for a log that cannot be read.
RigCalibration runMobileRigCalibration(const MobileRigCalibRequest& request);

}  // namespace sweepmap
