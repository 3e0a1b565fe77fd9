#include "calib/rotating_geometry.hpp"

#include <cmath>

namespace sweepmap {
namespace rotating {

double wrapAngle(double a) {
  a = std::remainder(a, 2.0 * M_PI);  // in [-pi, pi]
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

}  // namespace rotating
}  // namespace sweepmap
