// `sweepmap sim`: simulate any rig into an LCM log of its raw and ground-truth channels.
#include <iostream>
#include <memory>

#include "core/command_line.hpp"
#include "core/event_log.hpp"
#include "tools/cli/commands.hpp"
#include "tools/offline/runs.hpp"

namespace sweepmap {

namespace {

// Simulates the rig into the log `out`: 0, or 1 when the run did not make what was asked.
int simulateInto(const SimSetup& setup, const std::string& out, uint64_t seed, int sweeps) {
  checkOutputFile(out);
  SimRunOptions options;
  options.seed = seed;
  options.sweeps = sweeps;
  options.progress = true;
  std::unique_ptr<EventLogWriter> log;
  try {
    log = std::make_unique<EventLogWriter>(out);
  } catch (const std::runtime_error& e) {
    throw CommandError(kExitDeviceIo, e.what());
  }
  const SimRunResult r = simulateRig(
      setup, options, [&](const Message& m) { log->write(m.utime, m.channel, m.data); });
  try {
    log->close();
  } catch (const std::runtime_error& e) {
    throw CommandError(kExitDeviceIo, out + ": " + e.what());
  }
  std::cerr << "sim: " << setup.rig.kindName() << ": " << r.summary << " -> " << out << "\n";
  return r.ok ? kExitOk : kExitBadInput;
}

}  // namespace

Runner addSimCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "sim",
      "Simulate a rig and write an LCM log of its raw and ground-truth channels, on a virtual "
      "clock, deterministic from the seed. rotating_lidar (rig A): the motor and lidar process "
      "classes against the simulated stepper, switch and lidar (MOTOR_*, SCAN_WINDOW, "
      "LIDAR_SCAN, TRUTH_*). mobile_lidar (rig B): the car with wheel encoders, IMU and vertical "
      "lidar driving sim.path (WHEEL_TICKS, IMU, LIDAR_SCAN, TRUTH_POSE, TRUTH_MOUNTING, "
      "TRUTH_MOBILE_RIG). "
      "rotating_profile (rig C): the profile sensor on its turntable sweeping the calibration "
      "plate once per pose (sim.plate_count) or the paper's test piece (PROFILE, "
      "TRUTH_PROFILE_RIG)");
  cmd->footer(
      "Exit status: 0 simulated; 1 the run did not make what was asked (a motor fault, fewer "
      "sweeps); 2 bad option, rig, scene or --out; 4 the log cannot be written.");
  struct Opts {
    std::string rig, scene, out;
    int mode = 0;
    int sweeps = 1;
    uint64_t seed = 1;
    std::vector<std::string> sets;
    bool print_config = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("--rig", o->rig, "rig file or name (rig_a, rig_b, rig_c, a path)")->required();
  cmd->add_option("--scene", o->scene,
                  "scene file or name (default: scene_conference_room for rotating_lidar, "
                  "scene_lab for mobile_lidar); rotating_profile: plate | test_piece (default: "
                  "its sim.scene)");
  auto* mode = cmd->add_option("--mode", o->mode,
                               "rotating_lidar: scan mode 1..7 (default: motor.mode of the rig)")
                   ->check(CLI::Range(1, 7));
  auto* sweeps = cmd->add_option("--sweeps", o->sweeps, "rotating_lidar: number of 3D sweeps")
                     ->capture_default_str()
                     ->check(atLeast(1));
  cmd->add_option("--seed", o->seed, "random seed of the simulated devices")->capture_default_str();
  cmd->add_option("--set", o->sets,
                  "override a config key: key=value (e.g. sim.path=loop); scene keys as "
                  "scene.<key> (repeatable)");
  cmd->add_option("--out", o->out, "output LCM log");
  cmd->add_flag("--print-config", o->print_config,
                "print every rig and scene key with its value, unit and meaning, then exit");
  return [o, mode, sweeps]() -> int {
    SimSetup setup;
    try {
      setup = loadSimSetup(o->rig, o->scene, o->sets);
      auto* rotating = std::get_if<RotatingLidarConfig>(&setup.rig.config);
      if (!rotating && (mode->count() || sweeps->count())) {
        throw ConfigError("--mode and --sweeps apply to rotating_lidar rigs; " + setup.rig.path +
                          " is a " + setup.rig.kindName() + " rig (its sim.* keys set the run)");
      }
      if (rotating && o->mode > 0) rotating->motor.mode = o->mode;  // 1..7, checked above
    } catch (const std::exception& e) {
      std::cerr << "sim: config error: " << e.what() << "\n";
      return kExitUsage;
    }
    if (o->print_config) {
      printSimConfig(std::cout, setup);
      return kExitOk;
    }
    if (o->out.empty()) throw ConfigError("--out LOG is required (or --print-config)");
    return simulateInto(setup, o->out, o->seed, o->sweeps);
  };
}

}  // namespace sweepmap
