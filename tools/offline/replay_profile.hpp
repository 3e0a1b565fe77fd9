// Offline replay of a rig-C log through the live processes' classes on the log player: the
// assembler (processes/profile_assembler_node.hpp: every PROFILE placed in frame O_r by the
// generalised Eq. 7 with the rig's geometry, nominal or its calibration file) and the mapper.
#pragma once

#include <cstdint>
#include <string>

#include "rigs/rotating_profile.hpp"

namespace sweepmap {

struct ProfileReplayResult {
  int64_t events = 0;
  int64_t profiles = 0;
  int64_t invalid = 0;  // malformed or non-finite profiles, skipped and counted
  int64_t points = 0;
  int sweeps = 0;
  bool log_error = false;  // truncated or corrupt log: outputs up to it were kept
  std::string error;
};

// Writes DIR/cloud.pcd (every point, metres, frame O_r), DIR/sweeps/sweep_NNNNNN.pcd (one per
// turntable sweep id), DIR/map.bt, DIR/derived.lcmlog (SWEEP_CLOUD, MAP_STATS, STATUS_*),
// DIR/summary.json and, with `plots`, DIR/top_view.png. Throws LogError if the log cannot be
// opened.
ProfileReplayResult replayProfileLog(const std::string& log_path, const RotatingProfileConfig& rig,
                                     const std::string& out_dir, bool plots = true,
                                     bool progress = false);

}  // namespace sweepmap
