// What the calibration workflows read from their logs: rig C's plate sweeps
// (calibrate_axis_offset.cpp, calibrate_rig_kinds.cpp) and rig A's sweeps with the scans they
// came from (calibrate_lidar_axis_offset.cpp, calibrate_rig.cpp). A log that cannot be read
// is said on stderr as "WHAT: ..." naming the log and, where there is one, the byte offset.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/progress.hpp"
#include "tools/offline/log_sweeps.hpp"
#include "tools/offline/profile_log.hpp"

namespace sweepmap {

// Every sweep of rig C's logs as a plate pose.
struct PlateSweeps {
  std::vector<PlanePoints> planes;       // subsampled, one per plate pose
  std::vector<size_t> full_points;       // each plane's points before subsampling
  std::vector<std::string> rejected;     // "SOURCE: N points (< MIN)"
  std::optional<ProfileLogTruth> truth;  // the first log's that has one
  double read_s = 0.0;
};

struct PlateSweepLimits {
  int min_points = 0;  // a sweep with fewer is rejected
  int max_points = 0;  // one with more is subsampled to it
};

// Every sweep of every log into *in; with `say_each`, a line per sweep on stderr. False after
// "WHAT: <the ProfileLogError>" if a log cannot serve (what was read stays in *in).
bool readPlateSweeps(const std::vector<std::string>& logs, const PlateSweepLimits& limits,
                     const std::string& what, bool say_each, PlateSweeps* in);

struct LidarLogReading {
  // Each sweep and the window's scans it was assembled from (LogSweepOptions::on_window_scans).
  std::function<void(const std::string& log, const AssembledSweep&, const std::vector<Scan2D>&)>
      take_sweep;
  // Each log's result once it is read (its truth, counters).
  std::function<void(const LogReadResult&)> took_log;
  Progress* progress = nullptr;  // a stage per log, updated by the byte offset; or none
};

// Every sweep of every log (rig A's) through r.take_sweep. False after "WHAT: cannot read log
// 'LOG': ..." if a log cannot be opened; a corrupt tail is said, its message added to
// *log_errors, and the sweeps before it are used.
bool readLidarLogs(const std::vector<std::string>& logs, const RotatingLidarConfig& rig,
                   const std::string& what, const LidarLogReading& r,
                   std::vector<std::string>* log_errors);

}  // namespace sweepmap
