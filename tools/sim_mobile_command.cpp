#include <iostream>

#include "core/event_log.hpp"
#include "tools/commands.hpp"
#include "tools/sim_mobile.hpp"

namespace sweepmap {

Runner addSimMobileCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "sim-mobile",
      "Simulate rig B (a differential-drive car with wheel encoders, an IMU and a vertical 2D "
      "lidar driving a circle or a loop) and write an LCM log of WHEEL_TICKS, IMU, LIDAR_SCAN "
      "and the ground truth TRUTH_POSE and TRUTH_MOUNTING");
  struct Opts {
    std::string rig, scene, out;
    uint64_t seed = 1;
    std::vector<std::string> sets;
    bool print_config = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("--rig", o->rig, "rig B config file (e.g. config/rig_b.yaml)")->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--scene", o->scene, "scene file (e.g. config/scene_lab.yaml)")->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--seed", o->seed, "random seed of the simulated devices")->capture_default_str();
  cmd->add_option("--set", o->sets,
                  "override a config key: key=value (e.g. sim.path=loop); scene keys as "
                  "scene.<key> (repeatable)");
  cmd->add_option("--out", o->out, "output LCM log");
  cmd->add_flag("--print-config", o->print_config,
                "print every rig and scene key with its value, unit and meaning, then exit");
  return [o]() {
    SimMobileOptions options;
    try {
      loadSimMobileConfig(o->rig, o->scene, o->sets, &options.rig, &options.scene);
    } catch (const std::exception& e) {
      std::cerr << "config error: " << e.what() << "\n";
      return 2;
    }
    if (o->print_config) {
      printSimConfig(std::cout, options.rig, o->rig, options.scene, o->scene);
      return 0;
    }
    if (o->out.empty()) {
      std::cerr << "sim-mobile: --out LOG is required\n";
      return 2;
    }
    options.seed = o->seed;
    SimMobileResult r;
    try {
      EventLogWriter log(o->out);
      r = simulateMobile(options, [&](const Message& m) { log.write(m.utime, m.channel, m.data); });
      log.close();
    } catch (const ConfigError& e) {
      std::cerr << "config error: " << e.what() << "\n";
      return 2;
    }
    std::cerr << "sim-mobile: " << options.rig.sim.path << " path, " << r.duration_s << " s, "
              << r.path_length_m << " m driven, " << r.scans << " scans, " << r.slip_events
              << " slip events, " << r.messages << " messages -> " << o->out << "\n";
    return 0;
  };
}

}  // namespace sweepmap
