// Geometry of a line-structured-light profile sensor on a turntable (rig C, Zhao 2021
// section 2, Eq. 1-7), and its generalisation with a tilted laser plane and an encoder zero.
//
// Frames and offsets, as Eq. 7 defines them:
//   O_r  the rig frame: Z_r on the turntable's axis, up; X_r, Y_r horizontal; origin on the
//        axis at the height of the sensor's origin.
//   S    the sensor: its laser plane is the plane x_S = 0, so a profile point is (0, y, z);
//        z_S along the sensor's axis (parallel to Z_r when the laser plane is not tilted),
//        y_S across the laser line.
//   M    the distance from the turntable's axis to the laser plane, along X_r (the length
//        |O_r A| of Eq. 2, A the foot of the perpendicular from the axis to the plane).
//   N    the distance within the laser plane from A to the sensor's origin O, along the
//        profile's y axis (|OA| of Eq. 1); a point at profile coordinate y lies L = N + y
//        from A (Eq. 3).
//   alpha  the turntable's angle, clockwise seen from above (the rotation Rz(-alpha)).
// Eq. 7 expands to  p_r = Rz(-alpha) * (M, -(N + y), z):  at alpha = 0 a profile point sits at
// x_r = M, y_r = -(N + y), z_r = z; the sensor frame is Rz(180 deg) about its origin (M, -N, 0)
// (x_S = -X_r, y_S = -Y_r, z_S = Z_r). The paper's text places O at (M, N, 0) with parallel
// axes: the same picture mirrored in Y_r, which changes no distance, plane fit or size.
// We implement the equation.
//
// Generalised (extra parameters, both 0 in Eq. 7):
//   laser_tilt  the laser plane's tilt from the axis: the sensor is turned by this angle about
//               its own y axis, so a point (0, y, z) sits at (z sin(tilt), y, z cos(tilt)) in
//               the untilted sensor frame;
//   encoder_zero  the turntable angle at encoder count 0: alpha = 2 pi counts / cpr + zero.
//   p_r = Rz(-alpha) * (M - z sin(tilt), -(N + y), z cos(tilt))
// The encoder zero turns the whole cloud about the axis: planes seen by the sensor cannot
// determine it (a gauge freedom), only a known direction in the scene can. A yaw of the laser
// line within the horizontal plane is the same kind of freedom (it moves the foot A) and is
// not a separate parameter.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/profile.hpp"

namespace sweepmap {

struct ProfileGeometry {
  double m_mm = 0.0;              // M: axis to laser plane, along X_r
  double n_mm = 0.0;              // N: foot A to the sensor's origin, along the profile's y
  double laser_tilt_rad = 0.0;    // tilt of the laser plane from the axis (about S's y)
  double encoder_zero_rad = 0.0;  // turntable angle at encoder count 0
};

// The turntable angle alpha [rad] of an encoder reading.
inline double turntableAngleRad(int64_t counts, int counts_per_revolution,
                                double encoder_zero_rad) {
  return 2.0 * M_PI * static_cast<double>(counts) / counts_per_revolution + encoder_zero_rad;
}

// The generalised Eq. 7, templated so Ceres can differentiate it: the profile point
// (0, y_mm, z_mm) seen at the encoder angle `encoder_rad` (2 pi counts / cpr, before the
// encoder zero), in frame O_r [mm]. With laser_tilt = encoder_zero = 0 it is Eq. 7.
template <class T>
Eigen::Matrix<T, 3, 1> profilePointInRigFrame(const T& m_mm, const T& n_mm, const T& tilt_rad,
                                              const T& encoder_zero_rad, double y_mm, double z_mm,
                                              double encoder_rad) {
  using std::cos;
  using std::sin;
  const T alpha = encoder_rad + encoder_zero_rad;
  const T x0 = m_mm - z_mm * sin(tilt_rad);
  const T y0 = -(n_mm + y_mm);
  const T c = cos(alpha), s = sin(alpha);
  // Rz(-alpha) * (x0, y0, z)
  return Eigen::Matrix<T, 3, 1>(c * x0 + s * y0, -s * x0 + c * y0, z_mm * cos(tilt_rad));
}

inline Eigen::Vector3d profilePointInRigFrame(const ProfileGeometry& g, double y_mm, double z_mm,
                                              double encoder_rad) {
  return profilePointInRigFrame<double>(g.m_mm, g.n_mm, g.laser_tilt_rad, g.encoder_zero_rad, y_mm,
                                        z_mm, encoder_rad);
}

// Eq. 7 exactly as printed (with its absolute values and arctangents), for tests and for
// the paper's grid search reference: (x_r, y_r, z_r) of (0, y_i, z_i) at angle alpha.
inline Eigen::Vector3d zhaoEq7(double m_mm, double n_mm, double alpha_rad, double y_mm,
                               double z_mm) {
  const double r = std::sqrt(m_mm * m_mm + (n_mm + y_mm) * (n_mm + y_mm));  // Eq. 3-4
  const double beta = std::atan(std::fabs(m_mm) / std::fabs(n_mm + y_mm));  // Eq. 5
  return Eigen::Vector3d(r * std::sin(beta - alpha_rad), -r * std::cos(alpha_rad - beta), z_mm);
}

// The sensor's pose in O_r at encoder angle `encoder_rad`: where its origin is and where its
// y and z axes point (unit vectors). Points (0, y, z) are origin + y * y_axis + z * z_axis.
struct SensorPose {
  Eigen::Vector3d origin, y_axis, z_axis;
};
inline SensorPose sensorPoseInRigFrame(const ProfileGeometry& g, double encoder_rad) {
  const Eigen::Vector3d o = profilePointInRigFrame(g, 0.0, 0.0, encoder_rad);
  return {o, profilePointInRigFrame(g, 1.0, 0.0, encoder_rad) - o,
          profilePointInRigFrame(g, 0.0, 1.0, encoder_rad) - o};
}

// Every point of a profile in O_r, in metres (floats): the generalised Eq. 7 at the profile's
// latched encoder angle. The one assembly of rig C: the live assembler
// (processes/profile_assembler_node.hpp) and therefore replay and demo use it.
inline std::vector<Eigen::Vector3f> profilePointsInRigFrameM(const ProfileGeometry& g,
                                                             const Profile& p) {
  const double encoder_rad = turntableAngleRad(p.encoder_counts, p.counts_per_revolution, 0.0);
  std::vector<Eigen::Vector3f> out;
  out.reserve(p.y_mm.size());
  for (size_t i = 0; i < p.y_mm.size() && i < p.z_mm.size(); ++i) {
    out.push_back(
        (profilePointInRigFrame(g, p.y_mm[i], p.z_mm[i], encoder_rad) * 1e-3).cast<float>());
  }
  return out;
}

}  // namespace sweepmap
