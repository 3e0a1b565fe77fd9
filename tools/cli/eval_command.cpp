// `sweepmap eval`: evaluate a rig with its paper's measures (tools/eval/eval.hpp).
#include <iostream>

#include "core/command_line.hpp"
#include "core/config.hpp"
#include "core/progress.hpp"
#include "tools/cli/commands.hpp"
#include "tools/eval/eval.hpp"

namespace sweepmap {

namespace {

// What each rig kind's evaluation measures, for --help.
const char* const kEvalFooter =
    "rotating_lidar (Yuan 2021 section 5, Appendix B): phi_error of every sweep (uncorrected "
    "C_O', corrected with beta by ray_plane and by centroid), E_map = d tan(phi_error) and the "
    "distance d50 where it reaches 50 mm, alpha calibrated by LM over the wall normals of the "
    "mode-7 sweeps (into DIR/plate_calibration.yaml), wall-plane deviations. The experiment: "
    "--sweeps-per-mode sweeps of each of the 7 modes, --calib-sweeps mode-7 sweeps for alpha, "
    "mode 1 with the naive action sequence (unless --no-naive).\n\n"
    "mobile_lidar (Miao 2022 section 5): trajectory RMSE of wheel odometry alone and of the EKF "
    "against the truth, top and side views, RANSAC planes of walls, floor and ceiling (ceiling "
    "normal, deviation histograms), the density D (Eq. 18-19), room dimensions L1-L3 from "
    "plane-to-plane distances against the scene's truth, and the double wall (ghost) where the "
    "drive returns to its start. The experiment simulates the 120 s calibration circle and one "
    "lap of the lab loop, calibrates the mounting from the circle with both methods (ours into "
    "DIR/mounting_calibration.yaml), draws the circle's double walls and the target before and "
    "after calibration (Fig. 6-7), evaluates the loop with our calibration beside the mounting "
    "before it, and reports mounting_error_mrad against the truth (~3 min). --logs takes one "
    "log; --compare-uncalibrated also assembles it with no mounting error.\n\n"
    "rotating_profile (Zhao 2021 section 4, Tables 1-2; --experiment only): simulates the plate "
    "in its m poses (DIR/logs/plate.lcmlog), calibrates M, N by ours (Ceres, with the laser "
    "tilt) and by the paper's grid (Algorithm 1, 1 mm over M 110-130, N 395-425), both timed, "
    "draws S(M, N) (Fig. 6); then scans the test piece --repeats times (DIR/logs/"
    "test_piece_K.lcmlog: seed+100+K, the piece 3 mm nearer or farther each time, the sampling "
    "phase shifted; its true sizes from TRUTH_TEST_PIECE) and measures Table 2's features "
    "(groove diameters by a PCL RANSAC circle + Ceres cylinder, depths and the rectangle's "
    "width by PCL RANSAC planes, its length from the top face's edges) with ours, the grid's "
    "result and the paper's wrong settings (truth M - 13, N - 14 and M + 7, N + 16). "
    "report.json: offset_error_mm, feature_error_pct (mean, std per feature and setting), "
    "paper_table2, checks, timings_s (the only part that differs between runs), ~15 s.\n\n"
    "Exit status: 0 evaluated; 1 a log is corrupt (after evaluating what came before) or holds "
    "nothing to evaluate (the report says why), or (rotating_profile) a feature was not "
    "measured under some setting or ours did not calibrate; 2 bad rig, scene or option, a "
    "missing log, or a non-empty --out (see --force); 4 an output cannot be written.\n"
    "Examples: sweepmap eval --experiment paper --rig rig_a --out eval_a\n"
    "          sweepmap eval --experiment paper --rig rig_b --out eval_b\n"
    "          sweepmap eval --experiment paper --rig rig_c --out eval_c";

}  // namespace

Runner addEvalCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "eval",
      "Evaluate a rig with its paper's measures, against the simulator's truth where the logs "
      "carry it, into DIR/report.json, DIR/report.md and PNG figures. Either --logs LOG... "
      "(existing logs) or --experiment paper (simulates the paper's experiment into DIR/logs/, "
      "calibrates, then evaluates). Same inputs and seed give identical files (rig C: report.json "
      "but its timings_s)");
  cmd->footer(kEvalFooter);
  auto q = std::make_shared<EvalRequest>();
  auto no_plots = std::make_shared<bool>(false);
  auto quiet = std::make_shared<bool>(false);
  auto* logs =
      cmd->add_option("--logs,--log", q->logs, "LCM logs to evaluate (sweepmap sim, lcm-logger)")
          ->check(CLI::ExistingFile);
  auto* exp =
      cmd->add_option("--experiment", q->experiment, "simulate and evaluate an experiment: paper")
          ->check(CLI::IsMember({"paper"}));
  logs->excludes(exp);
  cmd->add_option("--rig", q->rig,
                  "rig file or name (rig_a, rig_b, rig_c, a path): its kind decides")
      ->required();
  cmd->add_option("--scene", q->scene,
                  "scene file or name (--experiment; default: the rig kind's scene)");
  cmd->add_option("--out", q->out_dir, "output folder (new or empty; see --force)")->required();
  auto force = std::make_shared<bool>(false);
  cmd->add_flag("--force", *force, "empty a non-empty --out folder first");
  cmd->add_option("--set", q->overrides,
                  "override a config key: key=value; scene keys as scene.<key> with --experiment "
                  "(repeatable)");
  cmd->add_option(
         "--seed", q->seed,
         "base seed (--experiment). rotating_lidar: mode m uses seed+m, the alpha log "
         "seed+100, the naive log seed+200; mobile_lidar: the circle seed, the loop seed+1; "
         "rotating_profile: the plates seed, test-piece scan K seed+100+K")
      ->capture_default_str();
  cmd->add_option("--sweeps-per-mode", q->sweeps_per_mode,
                  "rotating_lidar --experiment: sweeps per mode (default 5)")
      ->check(atLeast(1));
  cmd->add_option(
         "--calib-sweeps", q->calib_sweeps,
         "rotating_lidar --experiment: mode-7 sweeps for the alpha calibration (default 50)")
      ->check(atLeast(1));
  cmd->add_flag("--no-naive", q->no_naive,
                "rotating_lidar --experiment: skip the naive-action-sequence sweeps of mode 1");
  cmd->add_option("--repeats", q->repeats,
                  "rotating_profile --experiment: test-piece scans per setting (default 10, "
                  "Table 2's ten measurements; at least 2)");
  cmd->add_flag("--compare-uncalibrated", q->compare_uncalibrated,
                "mobile_lidar --logs: also assemble with no mounting error and compare "
                "(--experiment always does)");
  cmd->add_flag("--no-plots", *no_plots, "skip the PNG figures");
  cmd->add_flag("--quiet", *quiet,
                "no progress lines on stderr (they show only when it is a terminal)");
  return [q, no_plots, quiet, force]() -> int {
    q->plots = !*no_plots;
    ProgressOptions po;
    po.enabled = !*quiet;
    q->progress = Progress("eval", po).active();
    prepareOutputDir(q->out_dir, *force);
    const EvalRunResult r = runEval(*q);  // a ConfigError: exit status 2
    std::cerr << "eval: " << r.summary << "\n";
    if (r.failed) {
      std::cerr << "eval: " << r.message << "\n";
      return kExitBadInput;
    }
    return kExitOk;
  };
}

}  // namespace sweepmap
