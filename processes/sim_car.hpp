// The simulated rig-B car shared by `sweepmap sim`, the live processes with simulated devices
// (sweepmap-odometry, sweepmap-lidar) and the emulators: built the same way from the rig, the
// scene and the seed everywhere, and its ground truth as messages.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "processes/node.hpp"
#include "rigs/mobile_lidar.hpp"
#include "sim/car_devices.hpp"
#include "sim/mobile.hpp"
#include "sim/scene.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/truth_mobile_rig_t.hpp"
#include "sweepmap/truth_mounting_t.hpp"

namespace sweepmap {

// Resolves sim.path_file relative to the rig file and validates the simulation keys.
// Throws ConfigError naming `rig_path` and the key.
void prepareSimMobileConfig(const std::string& rig_path, MobileLidarConfig* rig);

// The car of `rig` (its sim.* keys, validated) in `scene`, starting at start_utime.
std::unique_ptr<SimMobile> makeSimCar(const MobileLidarConfig& rig, const Scene& scene,
                                      uint64_t seed, int64_t start_utime);

// TRUTH_MOUNTING: the true and nominal mounting, where the world frame lies in the room.
truth_mounting_t truthMountingMessage(const MobileLidarConfig& rig, const SceneConfig& scene,
                                      const SimMobile& car, int64_t utime);
// TRUTH_MOBILE_RIG: the true wheels, track, lever arm, clock offset and gyro bias.
truth_mobile_rig_t truthMobileRigMessage(const MobileLidarConfig& rig, const SimMobile& car,
                                         int64_t utime);
// TRUTH_POSE.
pose2d_t truthPoseMessage(const TruthPose& truth);

// A live process with the simulated car's devices also publishes its ground truth, as
// `sweepmap sim` logs it: TRUTH_POSE as its time comes, TRUTH_MOUNTING and TRUTH_MOBILE_RIG at
// start and at 1 Hz.
class SimCarTruthNode : public Node {
 public:
  SimCarTruthNode(const MobileLidarConfig& rig, const SceneConfig& scene, const SimMobile* car);
  std::vector<std::string> subscriptions() const override { return {}; }

 protected:
  void handle(const Message&, Outbox&) override {}
  void advance(int64_t now_utime, Outbox& out) override;

 private:
  MobileLidarConfig rig_;
  SceneConfig scene_;
  const SimMobile* car_;
  SimCarTruth truth_;
  int64_t next_mounting_utime_ = 0;
};

}  // namespace sweepmap
