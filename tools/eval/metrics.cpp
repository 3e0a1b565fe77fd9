#include "tools/eval/metrics.hpp"

#include <Eigen/Geometry>  // cross
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sweepmap {

double mapErrorDistance(double phi_error_rad, double limit_m, double max_range_m) {
  const double t = std::abs(std::tan(phi_error_rad));
  if (t * max_range_m <= limit_m) return max_range_m;
  return limit_m / t;
}

DeviationStats::DeviationStats(double bin, double range)
    : bin_mm(bin),
      range_mm(range),
      bins(static_cast<size_t>(std::max(1.0, std::round(2.0 * range / bin))), 0) {}

void DeviationStats::add(double d_mm, double within_mm) {
  ++count;
  sum_sq_mm2 += d_mm * d_mm;
  if (std::abs(d_mm) <= within_mm) ++within;
  if (d_mm < -range_mm || d_mm >= range_mm || bins.empty()) {
    ++outside_range;
    return;
  }
  const size_t i = std::min(bins.size() - 1, static_cast<size_t>((d_mm + range_mm) / bin_mm));
  ++bins[i];
}

void DeviationStats::merge(const DeviationStats& o) {
  if (bins.empty()) {
    *this = o;
    return;
  }
  count += o.count;
  sum_sq_mm2 += o.sum_sq_mm2;
  within += o.within;
  outside_range += o.outside_range;
  for (size_t i = 0; i < bins.size() && i < o.bins.size(); ++i) bins[i] += o.bins[i];
}

std::string DeviationStats::rmsLabel() const {
  if (count == 0) return "no points";
  char text[48];
  std::snprintf(text, sizeof text, "RMS %.1f mm", rmsMm());
  return text;
}

double DeviationStats::rmsMm() const {
  return count > 0 ? std::sqrt(sum_sq_mm2 / static_cast<double>(count)) : 0.0;
}

double DeviationStats::shareWithin() const {
  return count > 0 ? static_cast<double>(within) / static_cast<double>(count) : 0.0;
}

double DeviationStats::binCenterMm(size_t i) const {
  return -range_mm + (static_cast<double>(i) + 0.5) * bin_mm;
}

std::vector<std::vector<double>> wallDeviationsMm(const std::vector<Eigen::Vector3f>& cloud,
                                                  const std::vector<PlaneForDeviation>& planes,
                                                  double band_m, double edge_trim_m) {
  const size_t n_planes = planes.size();
  // Points in exactly one band: a point in two bands sits at a corner of two planes.
  std::vector<std::vector<size_t>> members(n_planes);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud[i].cast<double>();
    int hit = -1;
    int hits = 0;
    for (size_t k = 0; k < n_planes; ++k) {
      if (std::abs(planes[k].normal.dot(p) + planes[k].offset) <= band_m) {
        hit = static_cast<int>(k);
        ++hits;
      }
    }
    if (hits == 1) members[static_cast<size_t>(hit)].push_back(i);
  }
  std::vector<std::vector<double>> out(n_planes);
  for (size_t k = 0; k < n_planes; ++k) {
    if (members[k].empty()) continue;
    const Eigen::Vector3d& n = planes[k].normal;
    // In-plane axes: along the wall (horizontal) and z.
    Eigen::Vector3d along = Eigen::Vector3d::UnitZ().cross(n);
    if (along.norm() < 1e-6) along = Eigen::Vector3d::UnitX();
    along.normalize();
    double s_min = 1e300, s_max = -1e300, z_min = 1e300, z_max = -1e300;
    for (size_t i : members[k]) {
      const Eigen::Vector3d p = cloud[i].cast<double>();
      s_min = std::min(s_min, along.dot(p));
      s_max = std::max(s_max, along.dot(p));
      z_min = std::min(z_min, p.z());
      z_max = std::max(z_max, p.z());
    }
    for (size_t i : members[k]) {
      const Eigen::Vector3d p = cloud[i].cast<double>();
      const double s = along.dot(p);
      if (s < s_min + edge_trim_m || s > s_max - edge_trim_m || p.z() < z_min + edge_trim_m ||
          p.z() > z_max - edge_trim_m) {
        continue;
      }
      out[k].push_back(1000.0 * (n.dot(p) + planes[k].offset));
    }
  }
  return out;
}

}  // namespace sweepmap
