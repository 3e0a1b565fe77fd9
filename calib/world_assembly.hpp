// World-frame assembly for a 2D lidar on a moving base (rig B, Miao 2022 Eq. 11-14):
//   p_W = T_WB(t) * T_BL * p_L,  T_BL = [R(gamma, beta, alpha) R_nominal | t_BL],
// with T_WB interpolated at each ray's own time (deskewing) from the planar pose track.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "core/angles.hpp"
#include "core/mounting.hpp"
#include "core/scan.hpp"
#include "odometry/wheel_odometry.hpp"

namespace sweepmap {

// A time-ordered track of planar poses; linear interpolation (heading along the shorter arc).
class PoseTrack {
 public:
  void add(int64_t utime, const Pose2& pose);    // later poses replace same-time ones
  std::optional<Pose2> at(int64_t utime) const;  // nothing outside [first, last]
  int64_t lastUtime() const { return poses_.empty() ? INT64_MIN : poses_.rbegin()->first; }
  void pruneBefore(int64_t utime);  // keeps one pose at or before utime
  size_t size() const { return poses_.size(); }
  const std::map<int64_t, Pose2>& poses() const { return poses_; }

 private:
  std::map<int64_t, Pose2> poses_;
};

Eigen::Isometry3d planarToIsometry(const Pose2& pose);

// Transforms the valid rays of `scan` into the world, each with the pose at its own time.
// Rays whose time the track does not cover are skipped and counted in `*uncovered`. With
// `intensities`, it is set to each returned point's intensity when the scan has one per ray,
// else emptied (a lidar that measures none).
std::vector<Eigen::Vector3f> scanToWorld(const Scan2D& scan, const PoseTrack& track,
                                         const Eigen::Isometry3d& T_BL, int* uncovered = nullptr,
                                         std::vector<float>* intensities = nullptr);

}  // namespace sweepmap
