#include "processes/world_assembler_node.hpp"

#include <cmath>

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/pose2d_t.hpp"

namespace sweepmap {

WorldAssemblerNode::WorldAssemblerNode(const WorldAssemblerConfig& config,
                                       const LidarMounting& mounting)
    : Node("world_assembler"), config_(config), T_BL_(mounting.T_BL()) {}

std::vector<std::string> WorldAssemblerNode::subscriptions() const {
  return {channels::kLidarScan, config_.pose_channel};
}

void WorldAssemblerNode::handle(const Message& msg, Outbox& out) {
  if (msg.channel == channels::kLidarScan) {
    lidar_scan_t m;
    if (!decodeMessage(msg, &m)) {
      reportError("invalid", "malformed lidar_scan_t");
      return;
    }
    Scan2D scan = fromLcm(m);
    const std::string why = validateScan(scan, config_.beam_count);
    if (!why.empty()) {
      reportError("invalid", "scan " + std::to_string(scan.seq) + " dropped: " + why);
      return;
    }
    config_.toOdometryClock(&scan);
    if (!pending_.empty() && scan.utime <= pending_.back().utime) {
      reportError("dropped", "scan " + std::to_string(scan.seq) + " out of order, dropped");
      return;
    }
    pending_.push_back(std::move(scan));
  } else {
    pose2d_t p;
    if (!decodeMessage(msg, &p) || !std::isfinite(p.x_m) || !std::isfinite(p.y_m) ||
        !std::isfinite(p.theta_rad)) {
      reportError("invalid", "malformed or non-finite pose2d_t on " + msg.channel);
      return;
    }
    track_.add(p.utime, {p.x_m, p.y_m, p.theta_rad});
  }
  assembleReady(msg.utime, false, out);
}

void WorldAssemblerNode::assembleReady(int64_t now_utime, bool flush, Outbox& out) {
  const int64_t wait_us = static_cast<int64_t>(config_.max_pose_wait_s * 1e6);
  while (!pending_.empty()) {
    const Scan2D& s = pending_.front();
    const int64_t last_ray = s.rayUtime(s.ranges_m.empty() ? 0 : s.ranges_m.size() - 1);
    const bool covered = track_.lastUtime() >= last_ray;
    const bool waited_out = pending_.back().utime - s.utime > wait_us;
    if (!covered && !waited_out && !flush) break;
    publishScan(now_utime, s, out);
    last_assembled_utime_ = s.utime;
    pending_.pop_front();
  }
  // Poses before the next scan (or the last assembled one) are no longer needed.
  track_.pruneBefore(pending_.empty() ? last_assembled_utime_ : pending_.front().utime);
}

void WorldAssemblerNode::publishScan(int64_t now_utime, const Scan2D& scan, Outbox& out) {
  int uncovered = 0;
  std::vector<float> intensities;
  const std::vector<Eigen::Vector3f> pts =
      scanToWorld(scan, track_, T_BL_, &uncovered, &intensities);
  if (uncovered > 0) count("rays_without_pose", uncovered);
  const auto mid = track_.at(scan.rayUtime(scan.ranges_m.size() / 2));
  if (!mid) {
    count("scans_without_pose");
    return;
  }
  const Eigen::Vector3d origin = planarToIsometry(*mid) * T_BL_.translation();
  cloud_chunk_t c;
  c.utime = scan.utime;
  c.sweep_id = next_id_++;
  c.mode = 0;
  c.chunk_index = 0;
  c.chunk_count = 1;
  c.total_points = static_cast<int32_t>(pts.size());
  c.frame = "world";
  c.corrected = false;
  c.phi_offset_rad = 0.0;
  for (int i = 0; i < 3; ++i) c.sensor_origin_m[i] = origin[i];
  c.npoints = static_cast<int32_t>(pts.size());
  c.xyz_m.reserve(pts.size());
  for (const auto& p : pts) c.xyz_m.push_back({p.x(), p.y(), p.z()});
  c.nintensities = static_cast<int32_t>(intensities.size());
  c.intensities = intensities;
  out.publish(channels::kSweepCloud, now_utime, c);
  count("scans");
  if (observer_) observer_(scan.utime, pts, intensities, origin);
}

void WorldAssemblerNode::finish(int64_t now_utime, Outbox& out) {
  assembleReady(now_utime, true, out);
}

}  // namespace sweepmap
