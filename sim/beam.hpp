// Lidars whose beam does not look along their motor angle. A triangulation lidar such as the
// YDLIDAR X4 has its laser beside the rotation axis: what it measures lies off the motor
// angle by an amount that depends on the range (the X4 development manual's AngCorrect, which
// the host adds to the motor angle the device reports).
#pragma once

#include <cmath>
#include <functional>

namespace sweepmap {

// The direction of the beam off the motor angle [rad] for the range measured along it [m];
// an empty function: the beam looks along the motor angle.
using BeamOffset = std::function<double(double range_m)>;

struct BeamHit {
  double bearing_rad = 0.0;  // where the beam looked
  double range_m = 0.0;      // 0: no return
};

// The beam of motor angle `motor_rad`: the direction b = motor + offset(range_at(b)), with
// range_at(b) the range a ray along b meets (0: none, and then no offset), found by iterating
// from the motor angle. Each step moves b by offset'(r) dr/db times the previous step, far
// below 1 except at grazing incidence, so a dozen steps settle to 1e-6 rad. Where they do not
// (at a depth edge no direction agrees with the range it meets: the spot falls in the
// triangulation's shadow) there is no return, along the motor angle.
inline BeamHit castBeam(double motor_rad, const BeamOffset& offset,
                        const std::function<double(double bearing_rad)>& range_at) {
  constexpr int kIterations = 12;
  constexpr double kSettledRad = 1e-6;
  double b = motor_rad;
  for (int k = 0; k < kIterations; ++k) {
    const double r = range_at(b);
    const double next = r > 0.0 ? motor_rad + offset(r) : motor_rad;
    if (std::fabs(next - b) <= kSettledRad) return {next, r};
    b = next;
  }
  return {motor_rad, 0.0};
}

}  // namespace sweepmap
