// `sweepmap eval` for any rig: dispatches on the rig's kind to its paper's evaluation
// (rotating_lidar: Yuan 2021, tools/eval/eval_rotating.hpp; mobile_lidar: Miao 2022,
// tools/eval/eval_mobile.hpp; rotating_profile: Zhao 2021, tools/eval/eval_profile.hpp), of
// existing logs or of a simulated experiment.
//
// The library, by job (rotating_* for rig A, mobile_* for rig B; internal headers in
// namespace sweepmap::eval):
//   eval_rotating, eval_mobile  the drivers: a log or an experiment, step by step
//   eval_profile*               rig C's experiment: driver, test-piece features, report, figures
//   metrics, *_metrics          the measures (E_map distance, deviations, phi_error, alpha,
//                               trajectory errors, room planes and dimensions, ghosts)
//   *_figures                   one function per PNG (figures.hpp collects them)
//   *_report                    report.json and report.md, the only files that use JSON
//   common.hpp                  number formatting, progress lines, a stopwatch
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sweepmap {

struct EvalRequest {
  std::string rig;                // path or name; its kind selects the evaluation
  std::vector<std::string> logs;  // evaluate these logs (mobile_lidar: exactly one) ...
  std::string experiment;         // ... or simulate this experiment ("paper")
  std::string scene;              // --experiment: scene path or name ("" = the kind's default)
  std::vector<std::string> overrides;
  std::string out_dir;
  uint64_t seed = 1;
  bool plots = true;
  bool progress = true;
  // rotating_lidar only (0 / false: the experiment's defaults)
  int sweeps_per_mode = 0;
  int calib_sweeps = 0;
  bool no_naive = false;
  // mobile_lidar only
  bool compare_uncalibrated = false;
  // rotating_profile only (-1: the experiment's 10)
  int repeats = -1;
};

struct EvalRunResult {
  bool failed = false;  // corrupt log, nothing to evaluate: the report says why
  std::string summary;  // one line for the user
  std::string message;  // why it failed
};

// Throws ConfigError for a bad rig, scene or an option the rig's kind does not take, and
// std::runtime_error for unusable arguments.
EvalRunResult runEval(const EvalRequest& request);

}  // namespace sweepmap
