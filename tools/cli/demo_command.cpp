// `sweepmap demo`: the main job (tools/ops/demo.hpp).
#include <iostream>
#include <memory>

#include "core/command_line.hpp"
#include "core/config.hpp"
#include "tools/cli/commands.hpp"
#include "tools/ops/demo.hpp"

namespace sweepmap {

Runner addDemoCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "demo",
      "The main job: run the rig's processes and `sweepmap record` as separate processes in a "
      "private "
      "network namespace with simulated devices, stop everything cleanly, replay the recorded "
      "log, and leave the log, clouds, maps and a PNG top view in the output directory. "
      "rotating_lidar: sweepmap-motor and -lidar (simulated stepper and lidar), -assembler, "
      "-mapper make --sweeps 3D sweeps of the default room (--devices emulated: the lidar is "
      "`sweepmap emulate ust10lx` driven over SCIP by the real driver). mobile_lidar: "
      "sweepmap-lidar (X4) and sweepmap-odometry (wheel board, IMU, EKF) drive one simulated "
      "car for the rig's sim.duration_s (a 60 s circle for rig_b), -assembler and -mapper "
      "build the world cloud and map (--devices emulated: `sweepmap emulate "
      "x4,hi219,wheel-board` on pseudo-terminals, opened by the real serial drivers). "
      "rotating_profile (rig C): sweepmap-profiler turns the simulated turntable through one "
      "sweep per plate pose (sim.plate_count; --scene test_piece: one sweep of the test "
      "piece) with the simulated profile sensor, -assembler places the profiles by Eq. 7, "
      "-mapper maps them; only simulated devices (no real-device drivers for rig C yet)");
  auto o = std::make_shared<DemoOptions>();
  cmd->add_option("--rig", o->rig, "rig file or name")->capture_default_str();
  cmd->add_option("--scene", o->scene,
                  "scene file or name (default: the rig kind's scene); rotating_profile: plate or "
                  "test_piece (default sim.scene)");
  cmd->add_option("--out", o->out, "output folder (new or empty; see --force)")
      ->capture_default_str();
  auto force = std::make_shared<bool>(false);
  cmd->add_flag("--force", *force, "empty a non-empty --out folder first");
  cmd->add_option("--set", o->overrides,
                  "override a rig key for every process: key=value (repeatable)");
  cmd->add_option("--mode", o->mode, "rotating_lidar: scan mode 1..7")
      ->capture_default_str()
      ->check(CLI::Range(1, 7));
  cmd->add_option("--sweeps", o->sweeps, "rotating_lidar: number of sweeps")
      ->capture_default_str()
      ->check(atLeast(1));
  cmd->add_option("--seed", o->seed, "simulation seed")->capture_default_str();
  cmd->add_option("--devices", o->devices,
                  "sim (the device processes simulate their devices) or emulated (`sweepmap "
                  "emulate` serves the simulated devices behind their protocols: a UST-10LX "
                  "over SCIP 2.0 on 127.0.0.1:10940, or rig B's X4, HI219 and wheel board on "
                  "pseudo-terminals, and the processes drive them with the real drivers)")
      ->capture_default_str()
      ->check(CLI::IsMember({"sim", "emulated"}));
  cmd->footer(
      "Exit status: 0 done; 1 a process did not end cleanly or the replay failed; 2 bad option "
      "or rig, or a non-empty --out (see --force).");
  return [o, force]() -> int {
    prepareOutputDir(o->out, *force);
    return runDemo(*o);  // a ConfigError: exit status 2
  };
}

}  // namespace sweepmap
