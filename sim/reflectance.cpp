#include "sim/reflectance.hpp"

#include <cmath>

namespace sweepmap {

double surfaceReflectivity(const std::string& name) {
  const auto starts = [&](const char* prefix) { return name.rfind(prefix, 0) == 0; };
  if (starts("wall_") || name == "door_lintel") return 0.7;
  if (name == "ceiling") return 0.8;
  if (name == "floor") return 0.3;
  if (name == "door_leaf") return 0.45;
  if (starts("table") || name == "cabinet") return 0.1;
  if (name == "stand_post") return 0.3;
  if (name == "target_board") return 0.9;
  if (name == "window_back") return 0.2;
  return 0.5;
}

float simulatedIntensity(double reflectivity, double cos_incidence, double range_m) {
  if (!(range_m > 0.0)) return 0.0f;
  return static_cast<float>(
      std::round(kMattWhiteAt0m * reflectivity * std::fabs(cos_incidence) / (1.0 + range_m)));
}

}  // namespace sweepmap
