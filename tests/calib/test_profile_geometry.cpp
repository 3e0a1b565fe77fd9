// Rig C's geometry (core/profile_geometry.hpp): the generalised Eq. 7 against the paper's
// Eq. 7 as printed, and what its extra parameters do.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "core/angles.hpp"
#include "core/profile_geometry.hpp"

namespace sweepmap {
namespace {

TEST(ProfileGeometry, ReducesToEq7WithoutTiltAndEncoderZero) {
  const ProfileGeometry g{123.0, 409.0, 0.0, 0.0};
  for (const double alpha_deg : {-170.0, -25.0, 0.0, 3.7, 25.0, 90.0, 181.0}) {
    for (const double y : {-90.0, 0.0, 55.5}) {
      for (const double z : {-400.0, -190.0, 0.0}) {
        const Eigen::Vector3d ours = profilePointInRigFrame(g, y, z, alpha_deg * kDegToRad);
        const Eigen::Vector3d paper = zhaoEq7(123.0, 409.0, alpha_deg * kDegToRad, y, z);
        EXPECT_LT((ours - paper).norm(), 1e-9) << "alpha " << alpha_deg << " y " << y;
      }
    }
  }
}

TEST(ProfileGeometry, OffsetsAreWhereEq7PutsThem) {
  // At alpha = 0: x_r = M (the laser plane is M from the axis), y_r = -(N + y), z_r = z.
  const ProfileGeometry g{123.0, 409.0, 0.0, 0.0};
  const Eigen::Vector3d p = profilePointInRigFrame(g, 10.0, -300.0, 0.0);
  EXPECT_NEAR(p.x(), 123.0, 1e-12);
  EXPECT_NEAR(p.y(), -419.0, 1e-12);
  EXPECT_NEAR(p.z(), -300.0, 1e-12);
  // Every point of a profile stays M from the axis, measured perpendicular to the laser plane,
  // whatever the angle: the plane is tangent to the cylinder of radius M.
  for (const double a : {0.3, 1.1, -2.0}) {
    const SensorPose s = sensorPoseInRigFrame(g, a);
    const Eigen::Vector3d normal = s.y_axis.cross(s.z_axis);
    EXPECT_NEAR(std::fabs(normal.dot(s.origin)), 123.0, 1e-9);
  }
  // Clockwise seen from above: a quarter turn takes the point from -Y_r towards -X_r.
  const Eigen::Vector3d q = profilePointInRigFrame({0.0, 100.0, 0.0, 0.0}, 0.0, 0.0, M_PI / 2);
  EXPECT_NEAR(q.x(), -100.0, 1e-9);
  EXPECT_NEAR(q.y(), 0.0, 1e-9);
}

TEST(ProfileGeometry, EncoderZeroTurnsTheCloudAboutTheAxis) {
  const ProfileGeometry zero{123.0, 409.0, 0.0, 0.0}, shifted{123.0, 409.0, 0.0, 0.5 * kDegToRad};
  EXPECT_LT((profilePointInRigFrame(shifted, 20, -250, 0.1) -
             profilePointInRigFrame(zero, 20, -250, 0.1 + 0.5 * kDegToRad))
                .norm(),
            1e-9);
  EXPECT_DOUBLE_EQ(turntableAngleRad(65536, 262144, 0.25), M_PI / 2 + 0.25);
}

TEST(ProfileGeometry, TiltLeansTheLaserPlaneFromTheAxis) {
  const double tilt = 0.2 * kDegToRad;
  const ProfileGeometry g{123.0, 409.0, tilt, 0.0};
  // A point h below the origin moves by h sin(tilt) along the plane's normal (-X_r at 0).
  const Eigen::Vector3d p = profilePointInRigFrame(g, 0.0, -300.0, 0.0);
  EXPECT_NEAR(p.x(), 123.0 + 300.0 * std::sin(tilt), 1e-9);
  EXPECT_NEAR(p.z(), -300.0 * std::cos(tilt), 1e-9);
  // The laser plane's normal is off horizontal by the tilt.
  const SensorPose s = sensorPoseInRigFrame(g, 0.7);
  EXPECT_NEAR(std::asin(std::fabs(s.y_axis.cross(s.z_axis).z())), tilt, 1e-12);
}

}  // namespace
}  // namespace sweepmap
