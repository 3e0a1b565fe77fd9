// `sweepmap calib rig` and `sweepmap calib plan` as library calls: every parameter of a rig
// that its logs make observable, in one command, written as one calibration file that the rig
// file's `calibration_file` points to (core/calibration_file.hpp RigCalibrationFile). Rig A
// (rotating_lidar): calib/rig_a_calibration.hpp; rig B (mobile_lidar) and rig C
// (rotating_profile): tools/offline/calibrate_rig_kinds.hpp.
#pragma once

#include <string>
#include <vector>

#include "calib/axis_offset_lidar.hpp"
#include "calib/rig_a_calibration.hpp"
#include "rigs/rig_kind.hpp"
#include "rigs/rotating_lidar.hpp"

namespace sweepmap {

// Rig A's planes as `calib rig` segments them: at most this many rays per plane and sweep
// (evenly strided), and the rays within this many beams and scans of a depth edge left out (a
// door's jamb, a table's edge and mixed pixels there passed the gate, leaned the mirror offset
// by ~2.5 sigma under range noise, their weight under the Cauchy loss growing with the noise,
// and moved the offset). `calib axis-offset` leaves the depth edges out too.
constexpr int kRigCalibPlaneRays = 2000;
constexpr int kRigCalibDepthEdgeRays = 2;

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

// Rig A's joint solve as `calib rig` sets it up for `rig` (its values as the start and the
// nominal, its plate's model and region); the truth left empty.
RigAValues rigAValuesOf(const RotatingLidarConfig& rig);
RigASolveOptions rigASolveOptions(const RotatingLidarConfig& rig);

// The recommended recording of rig A, for the plan and the tests: sweeps of a full turn, so
// that the lidar sees the plate and the room from both sides of its scan plane.
struct RigARecording {
  int mode = 7;
  int sweeps = 10;
  int sweep_angle_deg = 360;
};

// The recommended recording of rig B: a figure-eight with a stop after every stop_interval_s
// of driving, duration_s long (about six laps: docs/explanation/results.md, rig B, "The
// plan's drive: 360 s").
struct RigBRecording {
  int duration_s = 360;
  int stop_interval_s = 20;
};

// `recording` as the rig file's sim.* values (key=value, for --set) that make it.
std::vector<std::string> rigBRecordingSets(const RigBRecording& recording);

// The `sweepmap sim` options after `--rig RIG` that make the recording calib plan recommends
// for `kind` (its "simulate:" line; `make bench` times calib rig on it), without --out.
std::vector<std::string> calibrationRecordingSimArgs(RigKind kind);

// The same as one line: the options joined by spaces.
std::string calibrationRecordingSimLine(RigKind kind);

}  // namespace sweepmap
