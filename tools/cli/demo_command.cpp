// `sweepmap demo`: the main job (tools/ops/demo.hpp).
#include <iostream>

#include "core/config.hpp"
#include "tools/cli/commands.hpp"
#include "tools/ops/demo.hpp"

namespace sweepmap {

Runner addDemoCommand(CLI::App& app, const std::string& argv0) {
  auto* cmd = app.add_subcommand(
      "demo",
      "The main job: start sweepmap-motor, -lidar (simulated devices), -assembler, -mapper and "
      "lcm-logger as separate processes in a private network namespace, make a few 3D sweeps "
      "of the default room, stop everything cleanly, replay the recorded log, and leave the "
      "log, per-sweep clouds, maps and a PNG top view in the output directory");
  auto o = std::make_shared<DemoOptions>();
  cmd->add_option("--rig", o->rig, "rig file or name")->capture_default_str();
  cmd->add_option("--scene", o->scene, "scene file or name (default: the rig kind's scene)");
  cmd->add_option("--out", o->out, "output directory")->capture_default_str();
  cmd->add_option("--mode", o->mode, "scan mode 1..7")->capture_default_str()->check(CLI::Range(1, 7));
  cmd->add_option("--sweeps", o->sweeps, "number of sweeps")->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o->seed, "simulation seed")->capture_default_str();
  return [o]() {
    try {
      return runDemo(*o);
    } catch (const ConfigError& e) {
      std::cerr << "config error: " << e.what() << "\n";
      return 2;
    }
  };
}

}  // namespace sweepmap
