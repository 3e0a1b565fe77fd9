// `sweepmap demo`: the main job. Starts the rig kind's processes and lcm-logger as separate
// processes in a private network namespace, with simulated devices, records a run, stops
// everything cleanly, replays the recorded log offline and leaves the log, clouds, maps and
// pictures in one directory.
//   rotating_lidar: sweepmap-motor and -lidar drive the simulated stepper and lidar;
//     -assembler and -mapper build the sweeps and the map. With devices "emulated" the
//     lidar is `sweepmap emulate ust10lx` (the same simulated lidar behind the SCIP 2.0
//     protocol on 127.0.0.1:10940) and sweepmap-lidar talks to it with the real driver.
//   mobile_lidar: the simulated car's raw channels (WHEEL_TICKS, IMU, LIDAR_SCAN and its
//     truth) are simulated into DIR/devices.lcmlog and played in real time by lcm-logplayer,
//     standing in for the wheel board, IMU and lidar drivers; sweepmap-odometry, -assembler
//     and -mapper process them live.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sweepmap {

struct DemoOptions {
  std::string rig = "rig_a";  // path or name; its kind decides the processes
  std::string scene;          // path or name; "" = the kind's default scene
  std::string out = "out";
  std::vector<std::string> overrides;  // rig keys for every process (and scene.<key>)
  int mode = 7;                        // rotating_lidar: scan mode
  int sweeps = 3;                      // rotating_lidar: 3D sweeps
  uint64_t seed = 1;
  // rotating_lidar: "sim" (sweepmap-lidar runs the simulated lidar in-process) or "emulated"
  // (`sweepmap emulate ust10lx` serves the simulated lidar as a UST-10LX over loopback TCP
  // and sweepmap-lidar drives it with the real SCIP 2.0 driver).
  std::string devices = "sim";
};

// Returns the exit status: 0 when every process ended cleanly and the replay has the run.
// Throws ConfigError for a bad rig or scene.
int runDemo(const DemoOptions& options);

}  // namespace sweepmap
