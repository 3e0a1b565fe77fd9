// Rig B's evaluation (Miao 2022 section 5): trajectory of odometry alone and of the EKF
// against the truth, top and side views of the world-frame cloud, RANSAC planes of the
// walls, floor and ceiling (ceiling normal, deviation histograms, Fig. 9), the density D of
// Eq. 18-19, the room's dimensions L1-L3 from plane-to-plane distances (Table 3) and the
// double wall ("ghost") where the drive comes back to its start. Writes DIR/report.json,
// DIR/report.md and PNG figures.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "calib/world_assembly.hpp"
#include "rigs/mobile_lidar.hpp"

namespace sweepmap {

struct EvalMobileOptions {
  std::string log_path;
  MobileLidarConfig rig;  // mounting.* is the mounting evaluated ("calibrated")
  std::string out_dir;
  bool plots = true;
  bool progress = true;
  // A mounting to compare with (before calibration: the nominal rotation without error):
  // its planes' deviations beside the evaluated mounting's. Unset: no comparison.
  std::optional<LidarMounting> before;
};

// The numbers are in out_dir/report.json.
struct EvalMobileResult {
  bool failed = false;  // corrupt log, no scans, no poses
  std::string message;
};

EvalMobileResult evalMobileLog(const EvalMobileOptions& options);

// --experiment paper: simulates the calibration circle and the lab loop into DIR/logs/,
// calibrates the mounting from the circle with both methods (ours into
// DIR/mounting_calibration.yaml), shows the circle's double walls before and after, evaluates
// the loop with our calibration (and with the mounting before it, for comparison) and
// reports each method's error against the simulator's truth.
struct MobileExperimentOptions {
  std::string rig_path = "rig_b";  // path or name (rigs/rig_file.hpp)
  std::string scene_path = "scene_lab";
  std::vector<std::string> overrides;  // scene.<key> to the scene, the rest to the rig
  std::string out_dir;
  uint64_t seed = 1;
  // The calibration circle: 4.6 laps at 0.2 m/s. Alpha is seen only through the track's
  // shift between antipodal passes, so more laps average the odometry's random walk down
  // (EKF track, seeds 1-5: |alpha error| <= 0.9 mrad with 120 s, up to 1.03 mrad with 60 s).
  double circle_duration_s = 120.0;
  double loop_duration_s = 140.0;  // one lap of the default loop (~126 s) and the closing overlap
  bool plots = true;
  bool progress = true;
};

// Throws ConfigError for a bad configuration.
EvalMobileResult runMobilePaperExperiment(const MobileExperimentOptions& options);

}  // namespace sweepmap
