// The triangular plate: extraction of its points from the semi-ring region of a sweep in
// frame O' and the angle beta of its middle line (Yuan 2021, section 4.1).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/rig_components.hpp"

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
  int points = 0;         // points in the region
  double beta_rad = 0.0;  // middle line in O' (valid when found)
  std::string reason;     // why not found
};

// Indices of the points of `cloud_Op` that lie in the region.
std::vector<size_t> extractPlatePoints(const std::vector<Eigen::Vector3f>& cloud_Op,
                                       const PlateRegion& region);

// The paper's estimator: beta = atan2 of the centroid of the region's points.
// Not found when fewer than `min_points` lie in the region.
PlateEstimate estimateBetaCentroid(const std::vector<Eigen::Vector3f>& cloud_Op,
                                   const PlateRegion& region, int min_points);

// One lidar ray in frame O' with its measured range.
struct PlateRay {
  Eigen::Vector3d origin;     // lidar centre at the ray's time
  Eigen::Vector3d direction;  // unit
  double range_m;             // measured
};

// The ray that meets the plate's plane z = region.z_center_m at a point of the semi-ring,
// or nothing. Returns the range to that point.
std::optional<double> plateRayRange(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                    const PlateRegion& region);

// Ray-plane estimator: every ray whose nominal intersection with the plate plane lies in
// the region and whose measured range is within `range_gate_m` of it contributes that
// intersection point, which carries no range noise. Selection depends on the noise only
// symmetrically (the gate), so the centroid's boundary bias of noisy points is avoided.
PlateEstimate estimateBetaRayPlane(const std::vector<PlateRay>& rays, const PlateRegion& region,
                                   double range_gate_m, int min_points);

// Consistency of a plate estimate with the plate's known shape (isosceles right triangle,
// hypotenuse `hypotenuse_m` at `base_distance_m` from the axis, middle line at beta), from
// every ray that meets the plate plane inside the region:
//  - expected: rays whose plane point lies on the plate at beta;
//  - on_plate: those whose range agrees with the plane (within the gate);
//  - in_front: those that end well before the plane (another object over the plate);
//  - off_plate: rays that agree with the plane but whose point is not on the plate at beta
//    (beta is off, or something flat lies in the region).
struct PlateCheck {
  int expected = 0;
  int on_plate = 0;
  int in_front = 0;
  int off_plate = 0;
  std::string problem;  // empty when the estimate is trustworthy
};
PlateCheck checkPlate(const std::vector<PlateRay>& rays, const PlateRegion& region, double beta_rad,
                      double hypotenuse_m, double base_distance_m, double range_gate_m);

}  // namespace sweepmap
