#include "core/scan.hpp"

#include <cmath>

namespace sweepmap {

std::string validateScan(const Scan2D& scan, int expected_beams) {
  if (expected_beams > 0 && scan.angles_rad.empty() &&
      scan.ranges_m.size() != static_cast<size_t>(expected_beams)) {
    return "wrong length: " + std::to_string(scan.ranges_m.size()) + " ranges, expected " +
           std::to_string(expected_beams);
  }
  if (!std::isfinite(scan.angle_min_rad) || !std::isfinite(scan.angle_increment_rad) ||
      !std::isfinite(scan.range_min_m) || !std::isfinite(scan.range_max_m) ||
      scan.range_min_m < 0.0 || scan.range_max_m <= scan.range_min_m ||
      scan.time_increment_ns < 0) {
    return "bad scan header";
  }
  const size_t n = scan.ranges_m.size();
  if (!scan.intensities.empty() && scan.intensities.size() != n) {
    return "wrong length: " + std::to_string(scan.intensities.size()) + " intensities for " +
           std::to_string(n) + " ranges";
  }
  if (!scan.angles_rad.empty() && scan.angles_rad.size() != n) {
    return "wrong length: " + std::to_string(scan.angles_rad.size()) + " angles for " +
           std::to_string(n) + " ranges";
  }
  for (size_t i = 0; i < scan.angles_rad.size(); ++i) {
    if (!std::isfinite(scan.angles_rad[i])) return "non-finite angle at ray " + std::to_string(i);
  }
  for (size_t i = 0; i < n; ++i) {
    const float r = scan.ranges_m[i];
    if (!std::isfinite(r)) return "non-finite range at ray " + std::to_string(i);
    if (r != 0.0f && (r < 0.0f || r > scan.range_max_m * 1.5)) {
      return "range out of limits at ray " + std::to_string(i) + ": " + std::to_string(r) + " m";
    }
  }
  return {};
}

}  // namespace sweepmap
