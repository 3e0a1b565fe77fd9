// Offline simulation of rig A: the motor and lidar process classes against the
// simulated stepper/switch and lidar, on a virtual clock, in one thread.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "core/rig_config.hpp"
#include "drivers/scene.hpp"
#include "processes/node.hpp"

namespace sweepmap {

struct SimOptions {
  RigConfig rig;
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

// Loads rig and scene and applies `key=value` overrides: keys starting with "scene."
// go to the scene, all others to the rig. Throws ConfigError naming file/key.
// Splits `key=value` overrides: those starting with "scene." (prefix removed) go to the
// scene, the others to the rig.
void splitSimOverrides(const std::vector<std::string>& overrides,
                       std::vector<std::string>* rig_sets, std::vector<std::string>* scene_sets);

void loadSimConfig(const std::string& rig_path, const std::string& scene_path,
                   const std::vector<std::string>& overrides, RigConfig* rig, SceneConfig* scene);

}  // namespace sweepmap
