// Measures both rigs' evaluations share, exposed for tests: the distance at which the mapping
// error of Yuan 2021 Eq. 21 reaches its limit, and the statistics of point-to-plane
// deviations (Yuan 2021 Appendix B; Miao 2022 Fig. 9).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace sweepmap {

// Eq. 21: the distance d at which |d * tan(phi_error)| reaches `limit_m`, capped at
// `max_range_m` (phi_error = 0 gives max_range_m).
double mapErrorDistance(double phi_error_rad, double limit_m, double max_range_m);

// Deviation statistics of signed point-to-plane distances (mm).
struct DeviationStats {
  int64_t count = 0;
  double sum_sq_mm2 = 0.0;
  int64_t within = 0;         // |deviation| <= within_mm
  int64_t outside_range = 0;  // beyond the histogram range (kept out of the bins)
  double bin_mm = 2.0;
  double range_mm = 100.0;  // bins cover [-range, range]
  std::vector<int64_t> bins;
  DeviationStats() = default;
  DeviationStats(double bin_mm, double range_mm);
  void add(double deviation_mm, double within_mm);
  void merge(const DeviationStats& other);
  double rmsMm() const;
  // "RMS 3.2 mm", or "no points" when nothing was measured (an RMS of 0.0 would read as perfect).
  std::string rmsLabel() const;
  double shareWithin() const;  // 0 when empty
  double binCenterMm(size_t i) const;
};

// A plane n.p + offset = 0 (unit n), as found in a cloud.
struct PlaneForDeviation {
  Eigen::Vector3d normal;
  double offset = 0.0;
};

// Signed deviations (mm) of the points of `cloud` that belong to each plane by the rules
// of Appendix B (EvalSettings in eval_rotating.hpp: band, edge trim, not in another plane's
// band), one vector per plane.
std::vector<std::vector<double>> wallDeviationsMm(const std::vector<Eigen::Vector3f>& cloud,
                                                  const std::vector<PlaneForDeviation>& planes,
                                                  double band_m, double edge_trim_m);

}  // namespace sweepmap
