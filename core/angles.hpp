// Angle helpers every library shares: degree/radian constants, wrapping to (-pi, pi], the
// roll-pitch-yaw rotation, and rounding of reported values.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace sweepmap {

constexpr double kDegToRad = M_PI / 180.0;
constexpr double kRadToDeg = 180.0 / M_PI;

// The same angle in (-pi, pi] (exact: std::remainder, no trigonometry).
inline double wrapAngle(double angle_rad) {
  if (angle_rad > -M_PI && angle_rad <= M_PI) return angle_rad;  // remainder's own answer
  const double w = std::remainder(angle_rad, 2.0 * M_PI);        // in [-pi, pi]
  return w <= -M_PI ? w + 2.0 * M_PI : w;
}

// R(roll, pitch, yaw) = Rz(yaw) Ry(pitch) Rx(roll): rotate about x, then y, then z, all
// fixed axes (Miao 2022's R(gamma, beta, alpha)).
inline Eigen::Matrix3d rotationXYZ(double roll_rad, double pitch_rad, double yaw_rad) {
  return (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// `value` rounded to `decimals` places, for reports that must read the same run after run.
inline double roundTo(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

}  // namespace sweepmap
