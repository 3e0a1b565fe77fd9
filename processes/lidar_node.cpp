#include "processes/lidar_node.hpp"

#include <cmath>

#include "processes/channels.hpp"
#include "processes/convert.hpp"

namespace sweepmap {

LidarNode::LidarNode(const LidarConfig& config, LidarDevice* device)
    : Node("lidar"), config_(config), device_(device) {}

void LidarNode::advance(int64_t now_utime, Outbox& out) {
  DeviceHealth health = device_->health();
  for (const auto& [name, value] : health.counters) setCounter(name, value);
  for (const std::string& e : health.events) reportEvent(e);
  if (!health.fatal.empty() && !failed()) setFailed(health.fatal);
  for (const Scan2D& scan : device_->poll(now_utime)) {
    // The driver's scans carry their own angles: their length is the device's (a SCIP
    // reply covers the steps asked for), not checked against the rig's ray count.
    const std::string why = validateScan(scan, 0);
    if (!why.empty()) {
      reportError("invalid", "device scan " + std::to_string(scan.seq) + " dropped: " + why);
      continue;
    }
    count("scans");
    out.publish(channels::kLidarScan, now_utime, toLcm(scan));
  }
}

TruthFollowerNode::TruthFollowerNode(ShaftTrajectory* trajectory)
    : Node("truth_follower"), trajectory_(trajectory) {}

std::vector<std::string> TruthFollowerNode::subscriptions() const {
  return {channels::kTruthShaft};
}

void TruthFollowerNode::handle(const Message& msg, Outbox& out) {
  truth_shaft_t m;
  if (!decodeMessage(msg, &m) || !std::isfinite(m.angle_rad) || !std::isfinite(m.velocity_rad_s) ||
      !std::isfinite(m.accel_rad_s2)) {
    reportError("invalid", "malformed truth_shaft_t");
    return;
  }
  trajectory_->apply(fromLcm(m));
  count("segments");
}

}  // namespace sweepmap
