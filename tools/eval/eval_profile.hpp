// `sweepmap eval --experiment paper --rig rig_c`: Zhao 2021's experiment for rig C, simulated.
//  1. the plate in its m poses (DIR/logs/plate.lcmlog), calibrated by ours (Ceres) and by the
//     paper's grid (Algorithm 1, 1 mm over its interval), both timed; S(M, N) drawn (Fig. 6);
//  2. the test piece scanned `repeats` times (DIR/logs/test_piece_K.lcmlog: seed + 100 + K,
//     the piece 3 mm nearer or farther each time and the sampling phase shifted), its true
//     sizes read from the logs' TRUTH_TEST_PIECE;
//  3. Table 2's features measured on every scan under four settings: ours, the grid's, and
//     the paper's two wrong ones relative to the truth (M - 13, N - 14) and (M + 7, N + 16);
//  4. report.json, report.md and the figures.
// The measures are in eval_profile_features, report.json/report.md in eval_profile_report,
// the PNGs in eval_profile_figures.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sweepmap {

struct ProfileExperimentOptions {
  std::string rig_path = "rig_c";  // a rotating_profile rig file or name
  std::vector<std::string> overrides;
  std::string out_dir;
  uint64_t seed = 1;
  int repeats = 10;  // test-piece scans (Table 2: ten measurements)
  bool plots = true;
  bool progress = true;
};

struct EvalProfileResult {
  bool failed = false;  // a setting could not measure a feature, or ours did not calibrate
  std::string message;
  int figures = 0;
  int scans = 0;
};

// Throws ConfigError for a rig that is not rotating_profile, a bad override or fewer than 2
// repeats; anything else that stops the experiment (a log that does not read back) fails
// the result with the reason, and no report is written.
EvalProfileResult runProfilePaperExperiment(const ProfileExperimentOptions& options);

}  // namespace sweepmap
