#include <iostream>

#include "processes/cli_common.hpp"
#include "tools/commands.hpp"
#include "tools/eval_mobile.hpp"
#include "tools/eval_rotating.hpp"

namespace sweepmap {

namespace {

Runner addEvalMobile(CLI::App* eval) {
  auto* cmd = eval->add_subcommand(
      "mobile",
      "Rig B (Miao 2022 section 5): trajectory RMSE of wheel odometry alone and of the EKF "
      "against the truth, top and side views, RANSAC planes of walls, floor and ceiling (ceiling "
      "normal, deviation histograms), the density D (Eq. 18-19), room dimensions L1-L3 from "
      "plane-to-plane distances against the scene's truth, and the double wall (ghost) where the "
      "drive returns to its start. Writes DIR/report.json, DIR/report.md, DIR/cloud.pcd and PNG "
      "figures. Either --log LOG (truth-based figures need the simulator's TRUTH_POSE and "
      "TRUTH_MOUNTING) or --experiment paper (simulates the 120 s calibration circle and one "
      "lap of the lab loop into DIR/logs/, calibrates the mounting from the circle with both methods "
      "(ours into DIR/mounting_calibration.yaml), draws the circle's double walls and the target before "
      "and after calibration (Fig. 6-7), evaluates the loop with our calibration beside the mounting "
      "before it, and reports mounting_error_mrad against the truth). Same inputs and seed give "
      "identical files. Exit 1 when the log is corrupt (after evaluating what came before) or holds no "
      "scans or poses, 2 for a bad config");
  struct Opts {
    std::string log, experiment, rig = "config/rig_b.yaml", scene = "config/scene_lab.yaml", out;
    std::vector<std::string> sets;
    uint64_t seed = 1;
    bool compare_uncalibrated = false, no_plots = false, quiet = false;
  };
  auto o = std::make_shared<Opts>();
  auto* log = cmd->add_option("--log", o->log, "LCM log of a rig-B drive (sweepmap sim-mobile, lcm-logger)")
                  ->check(CLI::ExistingFile);
  auto* exp = cmd->add_option("--experiment", o->experiment,
                              "simulate and evaluate an experiment: paper (Miao 2022 section 5)")
                  ->check(CLI::IsMember({"paper"}));
  log->excludes(exp);
  cmd->add_option("--rig", o->rig, "rig B config file")->capture_default_str()->check(CLI::ExistingFile);
  cmd->add_option("--scene", o->scene, "scene file (--experiment)")->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->add_option("--set", o->sets,
                  "override a config key: key=value; scene keys as scene.<key> with --experiment "
                  "(repeatable)");
  cmd->add_option("--seed", o->seed, "base seed (--experiment): the circle uses seed, the loop seed+1")
      ->capture_default_str();
  cmd->add_flag("--compare-uncalibrated", o->compare_uncalibrated,
                "also assemble with no mounting error (gamma = beta = alpha = 0) and compare "
                "(--log; --experiment always does)");
  cmd->add_flag("--no-plots", o->no_plots, "skip the PNG figures");
  cmd->add_flag("--quiet", o->quiet, "no progress lines on stderr");
  return [o, cmd]() {
    if (!cmd->parsed()) return 1;
    EvalMobileResult r;
    if (!o->experiment.empty()) {
      MobileExperimentOptions mo;
      mo.rig_path = o->rig;
      mo.scene_path = o->scene;
      mo.overrides = o->sets;
      mo.out_dir = o->out;
      mo.seed = o->seed;
      mo.plots = !o->no_plots;
      mo.progress = !o->quiet;
      try {
        r = runMobilePaperExperiment(mo);
      } catch (const ConfigError& e) {
        std::cerr << "config error: " << e.what() << "\n";
        return 2;
      }
    } else if (!o->log.empty()) {
      CommonOptions common;
      common.rig_b_path = o->rig;
      common.overrides = o->sets;
      EvalMobileOptions eo;
      eo.rig = loadRigBOrExit(common);
      eo.log_path = o->log;
      eo.out_dir = o->out;
      eo.plots = !o->no_plots;
      eo.progress = !o->quiet;
      if (o->compare_uncalibrated) {
        LidarMounting before = eo.rig.mounting.toMounting();
        before.gamma_rad = before.beta_rad = before.alpha_rad = 0.0;
        eo.before = before;
      }
      r = evalMobileLog(eo);
    } else {
      std::cerr << "eval mobile: give --log LOG or --experiment paper\n";
      return 2;
    }
    std::cerr << "eval mobile: -> " << o->out << "/report.json\n";
    if (r.failed) {
      std::cerr << "eval mobile: " << r.message << "\n";
      return 1;
    }
    return 0;
  };
}

}  // namespace

Runner addEvalCommand(CLI::App& app) {
  auto* eval = app.add_subcommand("eval", "Evaluate a rig with its paper's measures");
  eval->require_subcommand(1);
  auto* cmd = eval->add_subcommand(
      "rotating",
      "Rig A (Yuan 2021 section 5, Appendix B): phi_error of every sweep (uncorrected C_O', "
      "corrected with beta by ray_plane and by centroid), E_map = d tan(phi_error) and the "
      "distance d50 where it reaches 50 mm, alpha calibrated by LM over the wall normals of "
      "the mode-7 sweeps, wall-plane deviations. Writes DIR/report.json, DIR/report.md and "
      "PNG figures. Either --logs LOG... (existing logs; phi_error needs the simulator's "
      "truth channels) or --experiment paper (simulates the paper's experiment into "
      "DIR/logs/, calibrates alpha into DIR/plate_calibration.yaml, then evaluates). "
      "Exit 1 when a log is corrupt or no sweep was found (the report says why)");
  struct Opts {
    std::vector<std::string> logs;
    std::string experiment;
    std::string rig = "config/rig_a.yaml";
    std::string scene = "config/scene_conference_room.yaml";
    std::string out;
    std::vector<std::string> sets;
    uint64_t seed = 1;
    int sweeps_per_mode = 5;
    int calib_sweeps = 50;
    bool no_naive = false;
    bool no_plots = false;
    bool quiet = false;
  };
  auto o = std::make_shared<Opts>();
  auto* logs = cmd->add_option("--logs", o->logs, "LCM logs to evaluate (sweepmap sim, lcm-logger)")
                   ->check(CLI::ExistingFile);
  auto* exp = cmd->add_option("--experiment", o->experiment,
                              "simulate and evaluate an experiment: paper (Yuan 2021 section 5)")
                  ->check(CLI::IsMember({"paper"}));
  logs->excludes(exp);
  cmd->add_option("--rig", o->rig, "rig config file")->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_option("--scene", o->scene, "scene file (--experiment)")->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->add_option("--set", o->sets,
                  "override a config key: key=value; scene keys as scene.<key> with "
                  "--experiment (repeatable)");
  cmd->add_option("--seed", o->seed,
                  "base seed (--experiment): mode m uses seed+m, the alpha log seed+100, the "
                  "naive log seed+200")
      ->capture_default_str();
  cmd->add_option("--sweeps-per-mode", o->sweeps_per_mode, "sweeps per mode (--experiment)")
      ->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--calib-sweeps", o->calib_sweeps,
                  "mode-7 sweeps for the alpha calibration (--experiment)")
      ->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_flag("--no-naive", o->no_naive,
                "skip the naive-action-sequence sweeps of mode 1 (--experiment)");
  cmd->add_flag("--no-plots", o->no_plots, "skip the PNG figures");
  cmd->add_flag("--quiet", o->quiet, "no progress lines on stderr");

  Runner mobile = addEvalMobile(eval);
  return [o, cmd, mobile]() {
    if (!cmd->parsed()) return mobile();
    EvalSettings settings;
    settings.plots = !o->no_plots;
    settings.progress = !o->quiet;
    EvalRotatingResult r;
    if (!o->experiment.empty()) {
      PaperExperimentOptions po;
      po.rig_path = o->rig;
      po.scene_path = o->scene;
      po.overrides = o->sets;
      po.out_dir = o->out;
      po.seed = o->seed;
      po.sweeps_per_mode = o->sweeps_per_mode;
      po.calib_sweeps = o->calib_sweeps;
      po.naive = !o->no_naive;
      po.settings = settings;
      try {
        r = runPaperExperiment(po);
      } catch (const ConfigError& e) {
        std::cerr << "config error: " << e.what() << "\n";
        return 2;
      }
    } else if (!o->logs.empty()) {
      CommonOptions common;
      common.rig_path = o->rig;
      common.overrides = o->sets;
      EvalRotatingOptions eo;
      eo.rig = loadRigOrExit(common);
      eo.rig_path = o->rig;
      eo.overrides = o->sets;
      eo.logs = o->logs;
      eo.out_dir = o->out;
      eo.settings = settings;
      r = evalRotatingLogs(eo);
    } else {
      std::cerr << "eval rotating: give --logs LOG... or --experiment paper\n";
      return 2;
    }
    std::cerr << "eval rotating: " << r.sweeps << " sweeps, " << r.figures.size()
              << " figures -> " << o->out << "/report.md\n";
    if (r.failed) {
      std::cerr << "eval rotating: " << r.message << "\n";
      return 1;
    }
    return 0;
  };
}

}  // namespace sweepmap
