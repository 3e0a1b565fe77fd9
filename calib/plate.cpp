#include "calib/plate.hpp"

#include <cmath>

namespace sweepmap {

PlateRegion PlateRegion::fromConfig(const PlateConfig& plate) {
  PlateRegion r;
  r.inner_radius_m = plate.region_inner_radius_mm * 1e-3;
  r.outer_radius_m = plate.region_outer_radius_mm * 1e-3;
  r.z_center_m = plate.height_mm * 1e-3;
  r.thickness_m = plate.region_thickness_mm * 1e-3;
  return r;
}

bool PlateRegion::contains(const Eigen::Vector3f& p) const {
  if (p.x() < 0.0f) return false;  // the half ring cut along Y'
  if (std::abs(double(p.z()) - z_center_m) > 0.5 * thickness_m) return false;
  const double rho2 = double(p.x()) * p.x() + double(p.y()) * p.y();
  return rho2 >= inner_radius_m * inner_radius_m && rho2 <= outer_radius_m * outer_radius_m;
}

std::vector<size_t> extractPlatePoints(const std::vector<Eigen::Vector3f>& cloud_Op,
                                       const PlateRegion& region) {
  std::vector<size_t> idx;
  for (size_t i = 0; i < cloud_Op.size(); ++i) {
    if (region.contains(cloud_Op[i])) idx.push_back(i);
  }
  return idx;
}

PlateEstimate estimateBetaCentroid(const std::vector<Eigen::Vector3f>& cloud_Op,
                                   const PlateRegion& region, int min_points) {
  PlateEstimate e;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const auto& p : cloud_Op) {
    if (!region.contains(p)) continue;
    sum += Eigen::Vector2d(p.x(), p.y());
    ++e.points;
  }
  if (e.points < min_points) {
    e.reason = "plate not found: " + std::to_string(e.points) + " points in the region, need " +
               std::to_string(min_points);
    return e;
  }
  e.found = true;
  e.beta_rad = std::atan2(sum.y(), sum.x());
  return e;
}

std::optional<double> plateRayRange(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                    const PlateRegion& region) {
  if (dir.z() >= -1e-9) return std::nullopt;  // does not go down to the plate
  const double t = (region.z_center_m - origin.z()) / dir.z();
  if (t <= 0.0) return std::nullopt;
  const Eigen::Vector3d p = origin + t * dir;
  if (!region.contains(p.cast<float>())) return std::nullopt;
  return t;
}

PlateEstimate estimateBetaRayPlane(const std::vector<PlateRay>& rays, const PlateRegion& region,
                                   double range_gate_m, int min_points) {
  PlateEstimate e;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const auto& ray : rays) {
    const auto t = plateRayRange(ray.origin, ray.direction, region);
    if (!t || std::abs(ray.range_m - *t) > range_gate_m) continue;
    const Eigen::Vector3d p = ray.origin + *t * ray.direction;
    sum += p.head<2>();
    ++e.points;
  }
  if (e.points < min_points) {
    e.reason = "plate not found: " + std::to_string(e.points) +
               " rays meet the plate plane in the region, need " + std::to_string(min_points);
    return e;
  }
  e.found = true;
  e.beta_rad = std::atan2(sum.y(), sum.x());
  return e;
}

PlateCheck checkPlate(const std::vector<PlateRay>& rays, const PlateRegion& region, double beta,
                      double hypotenuse_m, double base_distance_m, double gate_m) {
  PlateCheck c;
  const double half = 0.5 * hypotenuse_m;
  const double cb = std::cos(beta), sb = std::sin(beta);
  for (const auto& ray : rays) {
    const auto t = plateRayRange(ray.origin, ray.direction, region);
    if (!t) continue;
    const Eigen::Vector3d p = ray.origin + *t * ray.direction;
    // Plate frame: u along the middle line, v across it.
    const double u = cb * p.x() + sb * p.y();
    const double v = -sb * p.x() + cb * p.y();
    const bool on_shape = u >= base_distance_m && std::abs(v) <= half - (u - base_distance_m);
    const bool agrees = std::abs(ray.range_m - *t) <= gate_m;
    if (on_shape) {
      ++c.expected;
      if (agrees) ++c.on_plate;
      if (ray.range_m < *t - gate_m) ++c.in_front;
    } else if (agrees) {
      ++c.off_plate;
    }
  }
  const auto ratio = [](int a, int b) { return std::to_string(a) + " of " + std::to_string(b); };
  if (c.expected == 0) {
    c.problem = "plate not where beta puts it";
  } else if (c.in_front > c.expected / 10) {
    c.problem = "plate mixed with another object: " + ratio(c.in_front, c.expected) +
                " plate rays end in front of it";
  } else if (c.on_plate < (6 * c.expected) / 10) {
    c.problem =
        "plate partial or occluded: " + ratio(c.on_plate, c.expected) + " expected rays hit it";
  } else if (c.off_plate > (15 * c.on_plate) / 100) {
    c.problem = "plate points outside its expected extent: " + std::to_string(c.off_plate) +
                " besides " + std::to_string(c.on_plate) + " on it";
  }
  return c;
}

}  // namespace sweepmap
