#include "calib/world_assembly.hpp"

#include <cmath>

#include "calib/rotating_geometry.hpp"

namespace sweepmap {

void PoseTrack::add(int64_t utime, const Pose2& pose) { poses_[utime] = pose; }

std::optional<Pose2> PoseTrack::at(int64_t utime) const {
  if (poses_.empty()) return std::nullopt;
  auto hi = poses_.lower_bound(utime);
  if (hi == poses_.end()) return std::nullopt;
  if (hi->first == utime) return hi->second;
  if (hi == poses_.begin()) return std::nullopt;
  auto lo = std::prev(hi);
  const double f =
      static_cast<double>(utime - lo->first) / static_cast<double>(hi->first - lo->first);
  const Pose2& a = lo->second;
  const Pose2& b = hi->second;
  return Pose2{a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m),
               a.theta_rad + f * wrapAngle(b.theta_rad - a.theta_rad)};
}

void PoseTrack::pruneBefore(int64_t utime) {
  auto it = poses_.upper_bound(utime);
  if (it == poses_.begin()) return;
  --it;  // the last pose at or before utime stays
  poses_.erase(poses_.begin(), it);
}

Eigen::Isometry3d planarToIsometry(const Pose2& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotating::rotZ(p.theta_rad);
  T.translation() = Eigen::Vector3d(p.x_m, p.y_m, 0.0);
  return T;
}

std::vector<Eigen::Vector3f> scanToWorld(const Scan2D& scan, const PoseTrack& track,
                                         const Eigen::Isometry3d& T_BL, int* uncovered,
                                         std::vector<float>* intensities) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(scan.ranges_m.size());
  const bool with_intensity = scan.intensities.size() == scan.ranges_m.size();
  if (intensities) intensities->clear();
  int missing = 0;
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    if (!scan.validRange(i)) continue;
    const double r = scan.ranges_m[i];
    const auto pose = track.at(scan.rayUtime(i));
    if (!pose) {
      ++missing;
      continue;
    }
    const Eigen::Vector3d p_L = rotating::pointInLidar(r, scan.rayAngle(i));
    out.push_back((planarToIsometry(*pose) * (T_BL * p_L)).cast<float>());
    if (intensities && with_intensity) intensities->push_back(scan.intensities[i]);
  }
  if (uncovered) *uncovered = missing;
  return out;
}

}  // namespace sweepmap
