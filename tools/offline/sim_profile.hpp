// Offline simulation of rig C (Zhao 2021): the simulated profile sensor and turntable
// scanning the calibration plate in each of its poses (a sweep per pose) or the test piece;
// raw PROFILE messages and the truth TRUTH_PROFILE_RIG (at each sweep's start; the test
// piece's sizes and frame on TRUTH_TEST_PIECE), in time order, deterministic from the seed.
#pragma once

#include <cstdint>
#include <functional>

#include "processes/node.hpp"
#include "rigs/rotating_profile.hpp"

namespace sweepmap {

struct SimProfileResult {
  int64_t messages = 0;
  int64_t profiles = 0;
  int64_t points = 0;
  int sweeps = 0;
  double duration_s = 0.0;
};

// The scene is rig.sim.scene. Throws ConfigError for a configuration it cannot simulate.
SimProfileResult simulateRotatingProfile(const RotatingProfileConfig& rig, uint64_t seed,
                                         const std::function<void(const Message&)>& sink);

}  // namespace sweepmap
