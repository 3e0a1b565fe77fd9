// Rig-A part of `sweepmap bench`: simulation and offline replay speed (assembly + plate
// correction + OctoMap) as real-time factors for modes 1 and 7, points per second, one
// sweep's plate correction, and peak memory. Prints figures; asserts nothing.
#pragma once

#include <ostream>
#include <string>

namespace sweepmap {

struct RotatingBenchOptions {
  std::string rig = "rig_a";  // path or name
  std::string scene = "scene_conference_room";
  std::string work = "build/bench";  // scratch directory
  int sweeps = 2;                    // sweeps per mode
};

// Returns 0.
int benchRotating(const RotatingBenchOptions& options, std::ostream& out);

}  // namespace sweepmap
