// Offline simulation of rig A: the motor and lidar process classes against the
// simulated stepper/switch and lidar, on a virtual clock, in one thread.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "processes/node.hpp"
#include "rigs/rotating_lidar.hpp"
#include "sim/scene.hpp"

namespace sweepmap {

struct SimOptions {
  RotatingLidarConfig rig;
  SceneConfig scene;
  int sweeps = 1;
  uint64_t seed = 1;
  int64_t tick_us = 1000;  // controller/device polling period of the virtual clock
};

struct SimResult {
  int sweeps_done = 0;
  int64_t simulated_us = 0;
  int64_t messages = 0;
  bool motor_fault = false;
};

// Runs until the motor has done its sweeps (plus the lidar's delivery latency).
// Every raw and ground-truth message goes to `sink` in publication order.
SimResult simulate(const SimOptions& options, const std::function<void(const Message&)>& sink);

// Splits `key=value` overrides: those starting with "scene." (prefix removed) go to the
// scene, the others to the rig.
void splitSimOverrides(const std::vector<std::string>& overrides,
                       std::vector<std::string>* rig_sets, std::vector<std::string>* scene_sets);

}  // namespace sweepmap
