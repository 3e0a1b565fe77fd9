// Differential-drive wheel odometry (Miao 2022, Eq. 2-5): from the two wheel speeds the
// body's speed v and turn rate w, integrated as
//   x_k = x_{k-1} + v dt cos(theta),  y_k = y_{k-1} + v dt sin(theta),  theta_k = theta_{k-1} + w
//   dt.
#pragma once

#include <cmath>

namespace sweepmap {

struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
};

struct BodyTwist {
  double v_m_s = 0.0;    // forward speed of the axle's midpoint
  double w_rad_s = 0.0;  // turn rate, counter-clockwise
};

// Left/right wheel ground speeds -> body twist; wheel_distance_m between the wheels.
inline BodyTwist twistFromWheels(double v_left_m_s, double v_right_m_s, double wheel_distance_m) {
  return {0.5 * (v_left_m_s + v_right_m_s), (v_right_m_s - v_left_m_s) / wheel_distance_m};
}

// One step of Eq. 2-5 (heading used before it is advanced, as in the paper).
inline Pose2 integrateOdometry(const Pose2& p, const BodyTwist& t, double dt_s) {
  return {p.x_m + t.v_m_s * dt_s * std::cos(p.theta_rad),
          p.y_m + t.v_m_s * dt_s * std::sin(p.theta_rad), p.theta_rad + t.w_rad_s * dt_s};
}

// Encoder ticks over an interval -> wheel ground speed.
inline double wheelSpeedFromTicks(long ticks, double dt_s, int ticks_per_revolution,
                                  double wheel_radius_m) {
  return 2.0 * M_PI * wheel_radius_m * static_cast<double>(ticks) /
         (static_cast<double>(ticks_per_revolution) * dt_s);
}

}  // namespace sweepmap
