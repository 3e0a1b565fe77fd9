// `sweepmap replay`: a log through the rig kind's processes, offline and deterministic.
#include <iostream>

#include "core/command_line.hpp"
#include "tools/cli/commands.hpp"
#include "tools/offline/runs.hpp"

namespace sweepmap {

Runner addReplayCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "replay",
      "Replay an LCM log offline (virtual clock, log order) through the processes of the rig's "
      "kind. rotating_lidar: assembler and mapper: DIR/sweeps/*.pcd|.ply, DIR/map.bt, "
      "DIR/derived.lcmlog, DIR/summary.json, DIR/top_view.png. mobile_lidar: sweepmap-odometry "
      "(wheel odometry + EKF), the world-frame assembler (each ray with its own interpolated "
      "pose and the configured mounting) and the mapper: DIR/map.bt, DIR/cloud.pcd|.ply, "
      "DIR/derived.lcmlog, DIR/summary.json, DIR/top_view.png. rotating_profile: every PROFILE "
      "placed in the turntable frame O_r by the generalised Eq. 7 of Zhao 2021 with the rig's "
      "geometry (its calibration file if it names one): DIR/cloud.pcd|.ply, DIR/sweeps/*.pcd|.ply (one per "
      "turntable sweep), DIR/summary.json; malformed profiles are skipped and counted. Unknown "
      "channels are skipped. Corrupt regions and a truncated tail are skipped to the next good "
      "event header (as LCM's own reader does): every event outside them is replayed, the "
      "skipped byte ranges are reported (and in summary.json's error), and the exit status is 1");
  cmd->footer(
      "Exit status: 0 replayed; 1 the log is corrupt (outputs up to it kept), empty, or of "
      "another rig kind (nothing made: the message says what the rig needs and what the log "
      "holds); 2 bad option, rig, missing log or non-empty --out (see --force); 4 an output "
      "cannot be written.");
  struct Opts {
    std::string log, rig, out;
    std::vector<std::string> sets;
    bool no_plots = false, force = false, quiet = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("LOG", o->log, "LCM log (sweepmap sim, lcm-logger, sweepmap import)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--rig", o->rig,
                  "rig file or name the log was recorded with (rig_a, rig_b, rig_c)")
      ->required();
  cmd->add_option("--out", o->out, "output folder (new or empty; see --force)")->required();
  cmd->add_flag("--force", o->force, "empty a non-empty --out folder first");
  cmd->add_option("--set", o->sets, "override a rig config key: key=value (repeatable)");
  cmd->add_flag("--no-plots", o->no_plots, "skip the PNG top view");
  cmd->add_flag("--quiet", o->quiet, "no progress on stderr (it shows only on a terminal)");
  return [o]() -> int {
    const Rig rig = loadRig(o->rig, o->sets);  // a ConfigError: exit status 2
    prepareOutputDir(o->out, o->force);
    ReplayRunOptions options;
    options.log_path = o->log;
    options.out_dir = o->out;
    options.progress = !o->quiet;
    options.plots = !o->no_plots;
    const ReplayRunResult r = replayRig(rig, options);
    std::cerr << "replay: " << rig.kindName() << ": " << r.summary << " -> " << o->out << "\n";
    if (r.log_error) {
      std::cerr << "replay: " << r.error << " (outputs up to there kept)\n";
      return kExitBadInput;
    }
    if (r.nothing) {
      std::cerr << "replay: " << r.error << "\n";
      return kExitBadInput;
    }
    return kExitOk;
  };
}

}  // namespace sweepmap
