#include <iostream>

#include "tools/commands.hpp"
#include "tools/replay_mobile.hpp"

namespace sweepmap {

Runner addReplayMobileCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "replay-mobile",
      "Rig B: replay a log of WHEEL_TICKS, IMU and LIDAR_SCAN offline through sweepmap-odometry "
      "(wheel odometry + EKF), the world-frame assembler (each ray with its own interpolated "
      "pose and the configured mounting) and the mapper: DIR/map.bt, DIR/cloud.pcd, "
      "DIR/derived.lcmlog, DIR/summary.json, DIR/top_view.png");
  auto log = std::make_shared<std::string>();
  auto rig = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto sets = std::make_shared<std::vector<std::string>>();
  auto no_plots = std::make_shared<bool>(false);
  cmd->add_option("LOG", *log, "LCM log (e.g. from sweepmap import breezyslam)")->required();
  cmd->add_option("--rig", *rig, "rig B config (e.g. config/rig_b_mines_rover.yaml)")->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", *out, "output directory")->required();
  cmd->add_option("--set", *sets, "override a config key: key=value (repeatable)");
  cmd->add_flag("--no-plots", *no_plots, "skip the PNG");
  return [=]() {
    RigBConfig config;
    try {
      config = loadRigB(*rig, *sets);
    } catch (const std::exception& e) {
      std::cerr << "config error: " << e.what() << "\n";
      return 2;
    }
    const MobileReplayResult r = replayMobileLog(*log, config, *out, !*no_plots);
    std::cerr << "replay-mobile: " << r.events << " events, " << r.scans << " scans, " << r.points
              << " points -> " << *out << "\n";
    if (r.log_error) {
      std::cerr << "replay-mobile: " << r.error << " (outputs up to there kept)\n";
      return 1;
    }
    return 0;
  };
}

}  // namespace sweepmap
