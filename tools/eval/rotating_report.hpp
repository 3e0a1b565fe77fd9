// Rig A's report: what the evaluation measured (ReportInput) written as DIR/report.json and
// DIR/report.md, with the figures drawn into DIR (rotating_figures.hpp). Internal to
// tools/eval.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "tools/eval/eval_rotating.hpp"
#include "tools/eval/rotating_metrics.hpp"

namespace sweepmap::eval {

// The simulated paper experiment, for report.json's inputs.experiment.
struct ExperimentInputs {
  std::string scene;
  uint64_t seed = 1;
  int sweeps_per_mode = 0;
  int calib_sweeps = 0;
  bool naive = false;
  std::map<std::string, uint64_t> seeds;  // by log file
  RotatingLidarConfig rig;                // the simulated rig (its error model is reported)
};

// What was evaluated: logs given (`logs`) or an experiment simulated (`experiment`).
struct ReportInputs {
  std::string rig;
  std::vector<std::string> overrides;
  std::vector<std::string> logs;  // without an experiment
  std::optional<ExperimentInputs> experiment;
};

// Everything the report is made of.
struct ReportInput {
  ReportInputs inputs;
  std::map<int, Group> modes;
  std::optional<Group> naive;
  std::vector<LogStatus> logs;
  AlphaCalibration alpha, alpha_centroid;
  std::string alpha_source;
  bool alpha_applied = false;  // the mode logs were evaluated with the calibrated alphas
  double alpha_eval_deg = 0.0, alpha_eval_centroid_deg = 0.0;
  std::optional<double> alpha_true_rad;
  std::map<std::string, double> timings_s;  // seconds by step
  MapperConfig mapper;                      // the rig's: the 3D map picture's voxels
};

// Draws the figures, then writes report.json and report.md into `out`.
EvalRotatingResult writeReport(const std::filesystem::path& out, const ReportInput& in,
                               const EvalSettings& s);

}  // namespace sweepmap::eval
