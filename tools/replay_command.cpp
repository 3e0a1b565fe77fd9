#include <iostream>

#include "processes/cli_common.hpp"
#include "tools/commands.hpp"
#include "tools/replay.hpp"

namespace sweepmap {

Runner addReplayCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "replay",
      "Replay an LCM log offline through the assembler and mapper (virtual clock, log order): "
      "writes DIR/sweeps/*.pcd|.ply, DIR/map.bt, DIR/derived.lcmlog, DIR/summary.json, "
      "DIR/top_view.png. Unknown channels are skipped. A truncated or corrupt log is reported "
      "with its byte offset (exit 1) after keeping every output up to that point");
  struct Opts {
    std::string log, rig, out;
    std::vector<std::string> sets;
    bool no_plots = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("LOG", o->log, "LCM log (sweepmap sim, lcm-logger)")->required();
  cmd->add_option("--rig", o->rig, "rig config file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->add_option("--set", o->sets, "override a rig config key: key=value (repeatable)");
  cmd->add_flag("--no-plots", o->no_plots, "skip the PNG top view");
  return [o]() {
    CommonOptions common;
    common.rig_path = o->rig;
    common.overrides = o->sets;
    const RigConfig rig = loadRigOrExit(common);
    ReplayOptions options;
    options.log_path = o->log;
    options.out_dir = o->out;
    options.progress = true;
    options.plots = !o->no_plots;
    const ReplayResult r = replayLog(options, rig);
    std::cerr << "replay: " << r.events << " events, " << r.sweeps << " sweeps, " << r.points
              << " points -> " << o->out << "\n";
    if (r.log_error) {
      std::cerr << "replay: " << r.error << " (outputs up to there kept)\n";
      return 1;
    }
    return 0;
  };
}

}  // namespace sweepmap
