// Rig B's report: what the evaluation of one log measured (MobileEvaluation) and, for the
// paper experiment, the calibration from the circle (CircleCalibration), written as
// DIR/report.json and DIR/report.md. Internal to tools/eval.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "calib/mounting_calibration.hpp"
#include "tools/eval/figures.hpp"
#include "tools/eval/mobile_metrics.hpp"

namespace sweepmap::eval {

// Everything measured in one log.
struct MobileEvaluation {
  std::string log_name;  // file name
  MobileLog log;
  std::string pose_channel;  // the assembler's: WHEEL_ODOMETRY or the EKF's
  LidarMounting mounting;    // the mounting evaluated
  TrajectoryErrors odometry, ekf;
  std::vector<Eigen::Vector3f> cloud;  // world frame
  std::vector<int> scan_of_point;      // index into log.scans of each point's scan
  RoomMeasures room;
  // The cloud assembled with the mounting before calibration, when asked for.
  std::optional<LidarMounting> before_mounting;
  std::optional<RoomMeasures> before;
  double density_m = 0.0;  // D of Eq. 18-19
  LoopClosure loop;

  bool hasTruth() const { return log.truth.size() > 0; }
  // The poses the cloud is assembled with.
  const PoseTrack& track() const { return pose_channel == "WHEEL_ODOMETRY" ? log.wheels : log.ekf; }
};

// The paper experiment's calibration from the circle, reported with the loop.
struct CircleCalibration {
  MountingCalibrationResult ours, paper;
  std::optional<LidarMounting> truth;  // from the circle's TRUTH_MOUNTING
  // The circle's double walls by mounting ("before", "after"); empty if not measured.
  std::map<std::string, DoubleWalls> double_walls;
};

// report.json and report.md of `ev`; `circle` (may be null) adds the calibration; `figures`
// are every figure drawn (the circle's first), `figure_errors` those of the loop's figures.
void writeMobileReport(const std::filesystem::path& out, const MobileEvaluation& ev,
                       const CircleCalibration* circle, const std::vector<Figures::Entry>& figures,
                       const std::vector<std::string>& figure_errors);

// report.json of an experiment whose calibration failed: the calibration alone.
void writeCalibrationFailureReport(const std::filesystem::path& out,
                                   const CircleCalibration& circle);

}  // namespace sweepmap::eval
