// Reads an LCM log and hands every sweep the assembler builds from it to a callback, with
// the ground truth the log carries (simulated logs). Used by replay, calibration and
// evaluation, so they all see exactly the sweeps the live assembler would publish.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "calib/sweep_assembly.hpp"
#include "processes/node.hpp"
#include "rigs/rotating_lidar.hpp"

namespace sweepmap {

struct SweepTruth {
  std::optional<double> phi_true_rad;    // true phi_offset (shaft angle at the first ray)
  std::optional<double> alpha_true_rad;  // true plate angle
};

struct LogReadResult {
  int64_t events = 0;
  int64_t first_utime = 0;
  int64_t last_utime = 0;
  std::map<std::string, int64_t> skipped_channels;
  int64_t scans = 0, invalid = 0, dropped = 0;  // assembler counters
  // Sweeps published with scans missing, those scans, and sweeps whose window never came
  // (assembler counters; see processes/assembler_node.hpp).
  int64_t sweeps_incomplete = 0, scans_missing = 0, windows_missing = 0;
  bool log_error = false;  // truncated or corrupt log (everything before it was processed)
  std::string error;
  std::optional<double> alpha_true_rad;
  std::optional<double> lidar_offset_x_true_m;     // TRUTH_RIG's (simulated logs)
  std::optional<double> scan_plane_tilt_true_rad;  // TRUTH_RIG_ERRORS' (simulated logs)
  std::optional<double> mirror_offset_true_rad;
  std::optional<double> plate_thickness_true_m;
  std::string scene;
};

struct LogSweepOptions {
  // Extra nodes on the bus after the assembler (e.g. the mapper), and a sink for every
  // message the nodes publish (e.g. derived.lcmlog).
  std::vector<Node*> extra_nodes;
  std::function<void(const Message&)> sink;
  std::function<void(uint64_t offset, uint64_t size)> progress;
  // Called with every sweep and the window's scans it was assembled from, before on_sweep.
  std::function<void(const AssembledSweep&, const std::vector<Scan2D>&)> on_window_scans;
};

// Throws LogError if the log cannot be opened; a bad log later on is reported in the result.
LogReadResult forEachSweep(
    const std::string& log_path, const RotatingLidarConfig& rig,
    const std::function<void(const AssembledSweep&, const SweepTruth&)>& on_sweep,
    const LogSweepOptions& options = {});

}  // namespace sweepmap
