#include "processes/profile_assembler_node.hpp"

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/profile_t.hpp"

namespace sweepmap {

ProfileAssemblerNode::ProfileAssemblerNode(const ProfileGeometry& geometry)
    : Node("profile_assembler"), geometry_(geometry) {}

std::vector<std::string> ProfileAssemblerNode::subscriptions() const {
  return {channels::kProfile};
}

void ProfileAssemblerNode::handle(const Message& msg, Outbox& out) {
  profile_t m;
  if (!decodeMessage(msg, &m)) {
    reportError("invalid", "malformed profile_t on " + msg.channel);
    return;
  }
  if (const std::string why = validateProfile(m); !why.empty()) {
    reportError("invalid", "profile " + std::to_string(m.sequence) + " dropped: " + why);
    return;
  }
  if (has_last_ && m.utime <= last_utime_) {
    reportError("dropped", "profile " + std::to_string(m.sequence) + " out of order, dropped");
    return;
  }
  has_last_ = true;
  last_utime_ = m.utime;
  const Profile profile = fromLcm(m);
  const std::vector<Eigen::Vector3f> points = profilePointsInRigFrameM(geometry_, profile);
  count("profiles");
  count("points", static_cast<int64_t>(points.size()));
  if (observer_) observer_(profile, points);
  if (points.empty()) return;  // nothing to map
  const Eigen::Vector3d origin =
      sensorPoseInRigFrame(
          geometry_, turntableAngleRad(profile.encoder_counts, profile.counts_per_revolution, 0.0))
          .origin *
      1e-3;
  cloud_chunk_t c;
  c.utime = profile.utime;
  c.sweep_id = profile.sweep_id;
  c.mode = 0;
  c.chunk_index = 0;
  c.chunk_count = 1;
  c.total_points = static_cast<int32_t>(points.size());
  c.frame = "O_r";
  c.corrected = false;
  c.phi_offset_rad = 0.0;
  for (int i = 0; i < 3; ++i) c.sensor_origin_m[i] = origin[i];
  c.npoints = static_cast<int32_t>(points.size());
  c.xyz_m.reserve(points.size());
  for (const auto& p : points) c.xyz_m.push_back({p.x(), p.y(), p.z()});
  c.nintensities = 0;  // the profiler measures no intensity
  out.publish(channels::kSweepCloud, msg.utime, c);
}

}  // namespace sweepmap
