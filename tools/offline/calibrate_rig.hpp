// `sweepmap calib rig` and `sweepmap calib plan` as library calls: every parameter of a rig
// that its logs make observable, in one command, written as one calibration file that the rig
// file's `calibration_file` points to (core/calibration_file.hpp RigCalibrationFile). Rig A
// (rotating_lidar): calib/rig_a_calibration.hpp; rig B (mobile_lidar) and rig C
// (rotating_profile): tools/offline/calibrate_rig_kinds.hpp.
#pragma once

#include <string>
#include <vector>

#include "calib/axis_offset_lidar.hpp"
#include "rigs/rig_kind.hpp"

namespace sweepmap {

struct RigCalibRequest {
  std::vector<std::string> logs;
  std::string rig;                // rig file or name
  std::vector<std::string> sets;  // rig overrides, key=value
  std::string out;                // calibration file to write (YAML, atomically)
  bool json = false;              // the result as JSON on stdout (no progress)
  PlaneSegmentationOptions segmentation;
};

// Human report and progress on stderr; with `json` the result on stdout. Returns the exit
// status: 0 calibrated (file written); 1 nothing calibrated (no usable sweep, nothing
// observable, a corrupt log); 2 bad rig, a missing log or output folder; 4 OUT cannot be
// written.
int calibrateRigFromLogs(const RigCalibRequest& request);

// What to record for `rig`'s calibration and why, with the `sweepmap sim` command that makes
// that recording in simulation, on stdout. Returns the exit status (2: bad rig).
int printCalibrationPlan(const std::string& rig, const std::vector<std::string>& sets);

// The recommended recording of rig A, for the plan and the tests: sweeps of a full turn, so
// that the lidar sees the plate and the room from both sides of its scan plane.
struct RigARecording {
  int mode = 7;
  int sweeps = 10;
  int sweep_angle_deg = 360;
};

// The `sweepmap sim` options after `--rig RIG` that make the recording calib plan recommends
// for `kind` (its "simulate:" line; `make bench` times calib rig on it), without --out.
std::vector<std::string> calibrationRecordingSimArgs(RigKind kind);

// The same as one line: the options joined by spaces.
std::string calibrationRecordingSimLine(RigKind kind);

}  // namespace sweepmap
