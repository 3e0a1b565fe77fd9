// sweepmap-lidar: polls a LidarDevice (real or simulated) and publishes every valid scan
// raw on LIDAR_SCAN. Invalid device output is dropped and counted. The device driver's
// counters (checksum errors, resyncs, timeouts, reconnects, clock resets, ...) and events
// go into the status; a device that cannot be used (identity mismatch) fails the node.
#pragma once

#include "core/rig_components.hpp"
#include "devices/lidar_device.hpp"
#include "devices/shaft_trajectory.hpp"
#include "processes/node.hpp"

namespace sweepmap {

class LidarNode : public Node {
 public:
  LidarNode(const LidarConfig& config, LidarDevice* device);
  std::vector<std::string> subscriptions() const override { return {}; }

 protected:
  void handle(const Message& msg, Outbox& out) override {}
  void advance(int64_t now_utime, Outbox& out) override;

 private:
  LidarConfig config_;
  LidarDevice* device_;
};

// Keeps a simulated device's copy of the true shaft motion up to date from TRUTH_SHAFT
// when the simulated stepper runs in another process.
class TruthFollowerNode : public Node {
 public:
  explicit TruthFollowerNode(ShaftTrajectory* trajectory);
  std::vector<std::string> subscriptions() const override;

 protected:
  void handle(const Message& msg, Outbox& out) override;

 private:
  ShaftTrajectory* trajectory_;
};

}  // namespace sweepmap
