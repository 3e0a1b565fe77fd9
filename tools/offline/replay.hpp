// Offline, deterministic replay of a log through the assembler and mapper classes.
#pragma once

#include <cstdint>
#include <string>

#include "rigs/rotating_lidar.hpp"

namespace sweepmap {

struct ReplayOptions {
  std::string log_path;
  std::string out_dir;
  bool progress = false;  // progress bar on stderr
  bool plots = true;      // DIR/top_view.png
};

struct ReplayResult {
  int sweeps = 0;
  int sweeps_incomplete = 0;  // published with scans missing (lost on the way to the log)
  int64_t scans_missing = 0;
  int64_t windows_missing = 0;  // sweeps whose window never came
  int64_t events = 0;
  int64_t points = 0;
  double log_duration_s = 0.0;  // first to last event
  bool log_error = false;       // truncated or corrupt log: outputs up to it were kept
  std::string error;
};

// Writes DIR/sweeps/sweep_NNNNNN.{pcd,ply}, DIR/map.bt, DIR/derived.lcmlog,
// DIR/summary.json (and DIR/top_view.png). Throws for unusable arguments (no log file,
// unwritable DIR); a bad log is reported in the result after writing all outputs.
ReplayResult replayLog(const ReplayOptions& options, const RotatingLidarConfig& rig);

}  // namespace sweepmap
