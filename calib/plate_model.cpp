#include "calib/plate_model.hpp"

#include <cmath>

namespace sweepmap {
namespace {

double logistic(double s) { return 1.0 / (1.0 + std::exp(-s)); }

// Where the ray crosses the plane z = z_m, if it goes down to it.
std::optional<Eigen::Vector3d> crossing(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                        double z_m) {
  if (!(d.z() < -1e-9)) return std::nullopt;
  const double t = (z_m - o.z()) / d.z();
  if (!(t > 0.0)) return std::nullopt;
  return o + t * d;
}

}  // namespace

PlateModel PlateModel::fromConfig(const PlateConfig& plate) {
  PlateModel m;
  m.height_m = plate.height_mm * 1e-3;
  m.thickness_m = plate.thickness_mm * 1e-3;
  m.hypotenuse_m = plate.hypotenuse_mm * 1e-3;
  m.base_distance_m = plate.base_distance_mm * 1e-3;
  m.range_gate_m = plate.range_gate_mm * 1e-3;
  return m;
}

double plateCoverage(const PlateModel& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                     double angle_rad) {
  const auto top = crossing(o, d, m.height_m);
  if (!top) return 0.0;
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  const double k = 4.0 / m.edge_m;  // logistic slope: 0.12 .. 0.88 across edge_m
  const double half = 0.5 * m.hypotenuse_m;
  // Plate frame: u along the middle line (from the axis), v across it.
  const auto uv = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d(c * p.x() + s * p.y(), -s * p.x() + c * p.y());
  };
  const Eigen::Vector2d a = uv(*top);
  // Where the ray meets the solid: its upper surface, or, when it passes inside the
  // hypotenuse there and beyond it at the lower surface, the hypotenuse's face (the rays go
  // outward, so one edge decides both: the lower crossing beyond the hypotenuse). One smooth
  // edge for the two: a sum of a top and a face term had a notch of 1 / slope (0.5 mm) where
  // they meet, which the real plate has not, and turned alpha by ~0.02 deg.
  Eigen::Vector2d b = a;
  if (m.thickness_m > 0.0) {
    const auto bottom = crossing(o, d, m.height_m - m.thickness_m);
    if (bottom) b = uv(*bottom);
  }
  Eigen::Vector2d hit = a;
  if (a.x() < m.base_distance_m && b.x() > a.x()) {
    hit = a + std::min(1.0, (m.base_distance_m - a.x()) / (b.x() - a.x())) * (b - a);
  }
  // Inside both legs (|v| <= half - (u - base)) where it meets the solid.
  const double legs = half - (hit.x() - m.base_distance_m);
  return logistic(k * (b.x() - m.base_distance_m)) * logistic(k * (legs - hit.y())) *
         logistic(k * (legs + hit.y()));
}

std::vector<char> plateHits(const PlateModel& m, const std::vector<PlateRay>& rays) {
  std::vector<char> hits(rays.size(), 0);
  for (size_t i = 0; i < rays.size(); ++i) {
    const auto top = crossing(rays[i].origin, rays[i].direction, m.height_m);
    hits[i] = top && std::fabs(rays[i].range_m - (*top - rays[i].origin).norm()) <= m.range_gate_m;
  }
  return hits;
}

std::optional<double> plateCentroidMismatch(const PlateModel& m, const std::vector<PlateRay>& rays,
                                            double angle_rad, const std::vector<char>* given) {
  Eigen::Vector2d measured = Eigen::Vector2d::Zero(), predicted = Eigen::Vector2d::Zero();
  double hits = 0.0, weight = 0.0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const PlateRay& r = rays[i];
    const auto top = crossing(r.origin, r.direction, m.height_m);
    if (!top) continue;
    const bool hit = given ? (*given)[i] != 0
                           : std::fabs(r.range_m - (*top - r.origin).norm()) <= m.range_gate_m;
    if (hit) {
      measured += top->head<2>();
      hits += 1.0;
    }
    const double w = plateCoverage(m, r.origin, r.direction, angle_rad);
    predicted += w * top->head<2>();
    weight += w;
  }
  if (hits == 0.0 || !(weight > 0.0)) return std::nullopt;
  // Both sums' directions: the weights' totals do not change them.
  return std::atan2(predicted.x() * measured.y() - predicted.y() * measured.x(),
                    predicted.dot(measured));
}

PlateModelFit fitPlateModel(const PlateModel& m, const std::vector<PlateRay>& rays, int min_hits) {
  PlateModelFit f;
  Eigen::Vector2d measured = Eigen::Vector2d::Zero();
  for (const PlateRay& r : rays) {
    const auto top = crossing(r.origin, r.direction, m.height_m);
    if (!top || std::fabs(r.range_m - (*top - r.origin).norm()) > m.range_gate_m) continue;
    measured += top->head<2>();
    ++f.hits;
  }
  if (f.hits < min_hits) {
    f.reason = "plate not found: " + std::to_string(f.hits) +
               " rays meet the plate's surface in the region, need " + std::to_string(min_hits);
    return f;
  }
  // mismatch(a) = measured - predicted direction ~ a_true - a: a <- a + mismatch(a).
  double a = std::atan2(measured.y(), measured.x());
  for (int i = 0; i < 30; ++i) {
    const auto e = plateCentroidMismatch(m, rays, a);
    if (!e) {
      f.reason = "plate model: no ray covered";
      return f;
    }
    a += *e;
    f.residual_rad = *e;
    if (std::fabs(*e) < 1e-10) break;
  }
  f.found = true;
  f.angle_rad = a;
  return f;
}

}  // namespace sweepmap
