#include <iostream>

#include "core/event_log.hpp"
#include "tools/commands.hpp"
#include "tools/simulation.hpp"

namespace sweepmap {

Runner addSimCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "sim",
      "Simulate rig A (motor + lidar process classes against simulated devices, virtual "
      "clock) and write an LCM log of the raw and ground-truth channels");
  struct Opts {
    std::string rig, scene, out;
    int mode = 0;
    int sweeps = 1;
    uint64_t seed = 1;
    std::vector<std::string> sets;
    bool print_config = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("--rig", o->rig, "rig config file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--scene", o->scene, "scene file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--mode", o->mode, "scan mode 1..7 (default: motor.mode of the rig)")
      ->check(CLI::Range(1, 7));
  cmd->add_option("--sweeps", o->sweeps, "number of 3D sweeps")->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o->seed, "random seed of the simulated devices")->capture_default_str();
  cmd->add_option("--set", o->sets,
                  "override a config key: key=value; scene keys as scene.<key> (repeatable)");
  cmd->add_option("--out", o->out, "output LCM log");
  cmd->add_flag("--print-config", o->print_config,
                "print every rig and scene key with its value, unit and meaning, then exit");
  return [o]() {
    RigConfig rig;
    SceneConfig scene;
    try {
      loadSimConfig(o->rig, o->scene, o->sets, &rig, &scene);
      if (o->mode > 0) rig.motor.mode = o->mode;
    } catch (const std::exception& e) {
      std::cerr << "config error: " << e.what() << "\n";
      return 2;
    }
    if (o->print_config) {
      printSimConfig(std::cout, rig, o->rig, scene, o->scene);
      return 0;
    }
    if (o->out.empty()) {
      std::cerr << "sim: --out LOG is required\n";
      return 2;
    }
    SimOptions options;
    options.rig = rig;
    options.scene = scene;
    options.sweeps = o->sweeps;
    options.seed = o->seed;
    EventLogWriter log(o->out);
    const SimResult r =
        simulate(options, [&](const Message& m) { log.write(m.utime, m.channel, m.data); });
    log.close();
    std::cerr << "sim: " << r.sweeps_done << " sweeps in mode " << rig.motor.mode << ", "
              << r.simulated_us / 1e6 << " s simulated, " << r.messages << " messages -> "
              << o->out << "\n";
    if (r.motor_fault) {
      std::cerr << "sim: the motor controller faulted (see STATUS_MOTOR in the log)\n";
      return 1;
    }
    return r.sweeps_done == o->sweeps ? 0 : 1;
  };
}

}  // namespace sweepmap
