// `sweepmap calib plate-angle` as a library call: the plate's installation angle alpha of a
// rotating_lidar rig (rig A, Yuan 2021 section 4.2, Algorithm A1) from the walls of a
// rectangular room in the sweeps of its logs, written as a calibration file
// (core/calibration_file.hpp). The command line (tools/cli/calib_command.cpp) only fills the
// request.
#pragma once

#include <string>
#include <vector>

#include "calib/walls.hpp"

namespace sweepmap {

struct PlateAngleCalibRequest {
  std::vector<std::string> logs;  // LCM logs of the room (sweepmap sim, lcm-logger)
  std::string rig;                // rig file or name (rotating_lidar)
  std::vector<std::string> sets;  // rig overrides, key=value
  std::string out;                // calibration file to write (YAML, atomically)
  bool json = false;              // the result as JSON on stdout
  double voxel_m = WallExtractionOptions{}.voxel_m;  // the wall extraction's downsampling
};

// Reads every sweep of the logs, extracts each corrected sweep's four walls, runs the LM of
// Algorithm A1 over their normals and writes `out`. Human report (per sweep, result, timing)
// on stderr; with `json` the result on stdout. Returns the exit status: 0 calibrated, 1 no
// usable sweep, 2 bad rig, log or output path (the calibration file cannot be written).
int calibratePlateAngleFromLogs(const PlateAngleCalibRequest& request);

}  // namespace sweepmap
