// Rig-B part of `sweepmap bench`: EKF updates per second in process, the CPU share of the
// real sweepmap-odometry executable at HI219-like IMU rates (in a private network
// namespace, fed by lcm-logplayer at real-time pace), and the `sweepmap replay` real-time
// factor on a simulated circle and lab loop; and the joint calibration on several seeds (for
// the calibration part, tools/bench/bench_calibration.hpp). Prints figures; asserts nothing.
#pragma once

#include <ostream>
#include <string>

namespace sweepmap {

struct RigBBenchOptions {
  std::string rig = "rig_b";  // path or name
  std::string scene = "scene_lab";
  std::string work = "build/bench";
  std::string sweepmap_exe;      // the sweepmap executable (its replay is run as a command)
  std::string bin_dir;           // where sweepmap-odometry is ("" = skip the process part)
  double process_feed_s = 12.0;  // log time fed to sweepmap-odometry per IMU rate
  double circle_s = 60.0;        // simulated circle for the replay
  double loop_s = 130.0;         // simulated lab loop for the replay (one lap ~ 125 s)
  int rig_calib_seeds = 5;
};

// Returns 0; a part that cannot run (no network namespace) says why and is skipped.
int benchRigB(const RigBBenchOptions& options, std::ostream& out);

// `calib rig`'s joint calibration in this process on calib plan's drive, one per seed
// (rig_calib_seeds): its time, each parameter's error against the truth in sigmas, the room.
void benchRigBCalibrationSeeds(const RigBBenchOptions& options, std::ostream& out);

}  // namespace sweepmap
