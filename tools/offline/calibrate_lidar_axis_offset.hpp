// `sweepmap calib axis-offset --rig <rotating_lidar>` as a library call: rig A's lidar-to-axis
// offset t_L^O' (Yuan 2021 Eq. 5-6, nominal 13.9 mm) from room sweeps by the planarity of
// walls, floor and ceiling (calib/axis_offset_lidar.hpp), written as a calibration file
// (core/calibration_file.hpp) that the rig's geometry.calibration_file points to; the
// assembler (live and in replay) then places every point with it.
#pragma once

#include <string>
#include <vector>

#include "calib/axis_offset_lidar.hpp"

namespace sweepmap {

struct LidarAxisOffsetCalibRequest {
  std::vector<std::string> logs;  // rig A logs of a room (sweepmap sim, lcm-logger)
  std::string rig;                // rig file or name (rotating_lidar)
  std::vector<std::string> sets;  // rig overrides, key=value
  std::string out;                // calibration file to write (YAML, atomically)
  bool json = false;              // the result as JSON on stdout
  bool estimate_y = false;        // also the offset within the scan plane (reported only)
  PlaneSegmentationOptions segmentation;
};

// Reads the logs' sweeps, finds each sweep's planes, solves, writes `out`. Human report on
// stderr; with `json` the result on stdout. Returns the exit status: 0 calibrated; 1 not
// calibrated (no usable sweep or plane, the offset not observable from the planes); 2 bad
// rig, log or output path.
int calibrateLidarAxisOffsetFromLogs(const LidarAxisOffsetCalibRequest& request);

}  // namespace sweepmap
