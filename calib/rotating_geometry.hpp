// Geometry of a rotating 2D lidar (Yuan 2021, section 3.2, Eq. 4-10).
//
// Frames: L (lidar; scan plane Y_L-Z_L, Z_L the middle of the scan sector),
// O' (rotation axis frame at the start of a 3D scan; Z' the rotation axis, Y' along the
// start position), O (corrected frame, X the rig's front). O and O' share the origin and
// differ by phi_offset about Z.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/angles.hpp"

namespace sweepmap {
namespace rotating {

// Rotation about Z by `angle_rad` (Eq. 6, 9, 13).
inline Eigen::Matrix3d rotZ(double angle_rad) {
  return Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// Eq. 4: p_L = r [0, sin(theta), cos(theta)]^T.
inline Eigen::Vector3d pointInLidar(double range_m, double theta_rad) {
  return range_m * Eigen::Vector3d(0.0, std::sin(theta_rad), std::cos(theta_rad));
}

// Eq. 5-6 with R_L^O' = I, t_L^O' = (offset_x_m, 0, 0):
// p_O' = R_M(phi_motor) (p_L + t_L^O').
inline Eigen::Vector3d lidarToOPrime(const Eigen::Vector3d& p_L, double phi_motor_rad,
                                     double offset_x_m) {
  return rotZ(phi_motor_rad) * (p_L + Eigen::Vector3d(offset_x_m, 0.0, 0.0));
}

// Eq. 5-6 with R_L^O' = I and the whole offset t_L^O' = (x, y, z) [m]: x across the scan
// plane (the paper's 13.9 mm), y within it perpendicular to the axis, z along the axis.
// Planes see them differently (calib/axis_offset_lidar.hpp): z only moves the whole cloud
// along the axis, never observable; x and y bend vertical walls, observable from them.
inline Eigen::Vector3d lidarToOPrime(const Eigen::Vector3d& p_L, double phi_motor_rad,
                                     const Eigen::Vector3d& t_L_Op_m) {
  return rotZ(phi_motor_rad) * (p_L + t_L_Op_m);
}

// R_L^O' of a real build (Eq. 5-6 take I): the scan plane tilted by `tilt_rad` about Y_L
// (its normal X_L leans toward Z) after the mirror's angle zero offset `mirror_rad` about X_L
// (a ray reported at theta leaves at theta + mirror): Ry(tilt) Rx(-mirror).
inline Eigen::Matrix3d lidarRotation(double tilt_rad, double mirror_rad) {
  return (Eigen::AngleAxisd(tilt_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(-mirror_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// Eq. 7: phi_motor^k = k / K * sweep_angle.
inline double motorAngleFromIndex(long k, long K, double sweep_angle_rad) {
  return static_cast<double>(k) / static_cast<double>(K) * sweep_angle_rad;
}

// Eq. 7 by time instead of index: the shaft turns at constant angular velocity through
// the window, so the angle of a point is its time since the window's first ray times
// omega. Identical to Eq. 7 for evenly spaced points; exact with the lidar's per-ray
// timing and the blind part of each mirror turn.
inline double motorAngleFromTime(int64_t t_utime, int64_t t0_utime, double omega_rad_s) {
  return omega_rad_s * 1e-6 * static_cast<double>(t_utime - t0_utime);
}

// Eq. 10: phi_offset = alpha - beta, wrapped.
inline double phiOffset(double alpha_rad, double beta_rad) {
  return wrapAngle(alpha_rad - beta_rad);
}

// Eq. 8-9: p_O = R_O'^O p_O'.
inline Eigen::Vector3d oPrimeToO(const Eigen::Vector3d& p_Op, double phi_offset_rad) {
  return rotZ(phi_offset_rad) * p_Op;
}

}  // namespace rotating
}  // namespace sweepmap
