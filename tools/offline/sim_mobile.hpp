// Offline simulation of rig B (Miao 2022): the simulated car of sim/mobile.hpp
// driving through the scene; raw WHEEL_TICKS, IMU, LIDAR_SCAN and ground truth TRUTH_POSE,
// in time order, deterministic from the seed.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "processes/node.hpp"
#include "rigs/mobile_lidar.hpp"
#include "sim/scene.hpp"

namespace sweepmap {

struct SimMobileOptions {
  MobileLidarConfig rig;
  SceneConfig scene;
  uint64_t seed = 1;
};

struct SimMobileResult {
  int64_t messages = 0;
  int64_t scans = 0;
  int slip_events = 0;
  double duration_s = 0.0;
  double path_length_m = 0.0;  // true distance driven
};

// Every message goes to `sink` in time order (event time; LIDAR_SCAN when delivered, its
// utime field the first ray's time). Ties: TRUTH_MOUNTING and TRUTH_MOBILE_RIG (start, 1 Hz),
// TRUTH_POSE, WHEEL_TICKS, IMU, LIDAR_SCAN. Throws ConfigError for a configuration it cannot
// simulate.
SimMobileResult simulateMobile(const SimMobileOptions& options,
                               const std::function<void(const Message&)>& sink);

}  // namespace sweepmap
