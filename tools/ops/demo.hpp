// `sweepmap demo`: the main job. Starts the rig kind's processes and lcm-logger as separate
// processes in a private network namespace, with simulated devices, records a run, stops
// everything cleanly, replays the recorded log offline and leaves the log, clouds, maps and
// pictures in one directory.
//   rotating_lidar: sweepmap-motor and -lidar drive the simulated stepper and lidar;
//     -assembler and -mapper build the sweeps and the map. With devices "emulated" the
//     lidar is `sweepmap emulate ust10lx` (the same simulated lidar behind the SCIP 2.0
//     protocol on 127.0.0.1:10940) and sweepmap-lidar talks to it with the real driver.
//   mobile_lidar (rig B live): sweepmap-lidar (the X4) and sweepmap-odometry (the wheel board
//     and the IMU; wheel odometry and the EKF) drive one simulated car from an agreed start
//     time for the rig's sim.duration_s, -assembler (world frame) and -mapper process them.
//     With devices "emulated" the car's three devices are `sweepmap emulate
//     x4,hi219,wheel-board` on pseudo-terminals (symlinks in DIR/dev/), publishing the truth,
//     and the two processes open them with the real serial drivers.
//   rotating_profile (rig C live): sweepmap-profiler turns the simulated turntable through one
//     sweep per plate pose (sim.plate_count; one for the test piece), publishing the simulated
//     profile sensor's PROFILE and the truth; -assembler (Eq. 7) and -mapper process them.
//     Only `sim` devices (no real-device drivers for rig C yet).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sweepmap {

struct DemoOptions {
  std::string rig = "rig_a";  // path or name; its kind decides the processes
  std::string scene;  // path or name; "" = the kind's default scene (rig C: plate | test_piece)
  std::string out = "out";
  std::vector<std::string> overrides;  // rig keys for every process (and scene.<key>)
  int mode = 7;                        // rotating_lidar: scan mode
  int sweeps = 3;                      // rotating_lidar: 3D sweeps
  uint64_t seed = 1;
  // "sim": the device processes simulate their devices in-process; "emulated": `sweepmap
  // emulate` serves the simulated devices behind their protocols (rotating_lidar: a UST-10LX
  // over loopback TCP; mobile_lidar: X4, HI219 and wheel board on pseudo-terminals) and the
  // processes drive them with the real drivers.
  std::string devices = "sim";
};

// Returns the exit status: 0 when every process ended cleanly and the replay has the run.
// Throws ConfigError for a bad rig or scene.
int runDemo(const DemoOptions& options);

}  // namespace sweepmap
