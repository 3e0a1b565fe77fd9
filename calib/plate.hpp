// The triangular plate: extraction of its points from the semi-ring region of a sweep in
// frame O' and the angle beta of its middle line (Yuan 2021, section 4.1).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/rig_config.hpp"

namespace sweepmap {

// The semi-ring region around the rotation axis, cut along Y' (x' >= 0 half).
struct PlateRegion {
  double inner_radius_m = 0.0625;
  double outer_radius_m = 0.1155;
  double z_center_m = -0.045;
  double thickness_m = 0.020;

  static PlateRegion fromConfig(const PlateConfig& plate);
  bool contains(const Eigen::Vector3f& p_Op) const;
};

struct PlateEstimate {
  bool found = false;
  int points = 0;           // points in the region
  double beta_rad = 0.0;    // middle line in O' (valid when found)
  std::string reason;       // why not found
};

// Indices of the points of `cloud_Op` that lie in the region.
std::vector<size_t> extractPlatePoints(const std::vector<Eigen::Vector3f>& cloud_Op,
                                       const PlateRegion& region);

// The paper's estimator: beta = atan2 of the centroid of the region's points.
// Not found when fewer than `min_points` lie in the region.
PlateEstimate estimateBetaCentroid(const std::vector<Eigen::Vector3f>& cloud_Op,
                                   const PlateRegion& region, int min_points);

}  // namespace sweepmap
