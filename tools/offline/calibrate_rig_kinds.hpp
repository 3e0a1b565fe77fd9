// `sweepmap calib rig` and `calib plan` for rig B (mobile_lidar) and rig C (rotating_profile),
// on the rig-neutral result (calib/rig_calibration.hpp) that rig A's part fills too:
//  - rig C: the existing joint solver of the axis offsets (calib/axis_offset.hpp
//    solveAxisOffset: M, N, the laser-plane tilt and the encoder zero in one Ceres problem
//    over plate poses), written in the format `calib axis-offset` writes, which the rig's
//    geometry.calibration_file applies;
//  - rig B: runMobileRigCalibration (tools/offline/mobile_rig_calibration.hpp), every
//    calibrated key written as rig A's are (writeRigCalibrationOf), which the rig's
//    calibration_file applies.
#pragma once

#include <functional>
#include <string>

#include "calib/rig_calibration.hpp"
#include "rigs/rig_file.hpp"
#include "tools/offline/calibrate_rig.hpp"

namespace sweepmap {

// Writes the file through `write` when some parameter is observable (an exception from it:
// exit 4), then the human report on stderr and, with --json, the JSON on stdout. Returns the
// exit status of calibrateRigFromLogs.
int reportRigCalibration(const RigCalibRequest& request, const Rig& rig, double read_s,
                         const RigCalibration& result, const std::function<void()>& write);

// Writes the observable parameters of `result` as rig-file keys (core/calibration_file.hpp
// RigCalibrationFile) to request.out: the file a rig's top-level calibration_file applies.
void writeRigCalibrationOf(const RigCalibRequest& request, const Rig& rig,
                           const RigCalibration& result);

int calibrateProfileRig(const RigCalibRequest& request, const Rig& rig);
int calibrateMobileLidarRig(const RigCalibRequest& request, const Rig& rig);

int printProfileRigPlan(const std::string& rig_name, const Rig& rig);
int printMobileLidarRigPlan(const std::string& rig_name, const Rig& rig);

}  // namespace sweepmap
