// `sweepmap demo`: the main job. Starts the rig's processes and lcm-logger as separate
// processes in a private network namespace with simulated devices, records a run, stops
// everything cleanly, replays the recorded log offline and leaves the log, clouds, maps
// and pictures in one directory.
#pragma once

#include <cstdint>
#include <string>

namespace sweepmap {

struct DemoOptions {
  std::string rig = "rig_a";  // path or name; its kind decides the processes
  std::string scene;          // path or name; "" = the kind's default scene
  std::string out = "out";
  int mode = 7;               // rotating_lidar: scan mode
  int sweeps = 3;             // rotating_lidar: 3D sweeps
  uint64_t seed = 1;
};

// Returns the exit status: 0 when every process ended cleanly and the replay has all sweeps.
// Throws ConfigError for a bad rig or scene.
int runDemo(const DemoOptions& options);

}  // namespace sweepmap
