// `sweepmap calib mounting` as a library call: the 3-axis mounting error of a mobile_lidar
// rig's lidar (rig B, Miao 2022 section 4.2) from a drive that sees the same surfaces twice,
// by our point-to-plane method (the result written) and the paper's point pairs (reported
// beside it), written as a calibration file (core/calibration_file.hpp). The command line
// (tools/cli/calib_command.cpp) only fills the request.
#pragma once

#include <string>
#include <vector>

#include "calib/mounting_calibration.hpp"

namespace sweepmap {

struct MountingCalibRequest {
  std::string log;                // LCM log of the drive (sweepmap sim, lcm-logger)
  std::string rig;                // rig file or name (mobile_lidar)
  std::vector<std::string> sets;  // rig overrides, key=value
  std::string out;                // calibration file to write (YAML, atomically)
  bool json = false;              // the result as JSON on stdout
  std::string track = "ekf";      // poses: ekf (ODOMETRY_POSE replayed) | wheels | truth
  bool time_offset = false;       // also estimate the lidar-to-odometry time offset (ours)
  bool track_drift = false;       // also estimate the track's slow position drift (ours)
  bool no_paper = false;          // skip the paper's method (else reported beside ours)
  double min_pass_gap_s = MountingCalibrationOptions{}.min_pass_gap_s;
};

// Replays the log's odometry, runs both methods from the rig's mounting and writes ours to
// `out`. Human report on stderr; with `json` the result on stdout. Returns the exit status:
// 0 calibrated, 1 not calibrated (too little data, no overlap), 2 bad rig, log or output path.
int calibrateMountingFromLog(const MountingCalibRequest& request);

}  // namespace sweepmap
