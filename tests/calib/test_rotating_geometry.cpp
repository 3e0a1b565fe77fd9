#include <gtest/gtest.h>

#include <cmath>

#include "calib/rotating_geometry.hpp"
#include "core/angles.hpp"

namespace sweepmap {
namespace rotating {
namespace {

void expectNear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double tol = 1e-12) {
  EXPECT_LT((a - b).norm(), tol) << "got " << a.transpose() << " want " << b.transpose();
}

TEST(RotatingGeometry, Eq4PointInLidarFrame) {
  expectNear(pointInLidar(2.0, 0.0), {0, 0, 2});             // middle of the sector: Z_L
  expectNear(pointInLidar(2.0, 90 * kDegToRad), {0, 2, 0});  // toward Y_L
  expectNear(pointInLidar(1.0, -135 * kDegToRad), {0, -std::sqrt(0.5), -std::sqrt(0.5)});
}

TEST(RotatingGeometry, Eq5And6LidarToOPrime) {
  const double d = 0.0139;
  // phi = 0: only the offset along X'.
  expectNear(lidarToOPrime({0, 1, 0}, 0.0, d), {d, 1, 0});
  // phi = 90 deg: X_L -> Y', Y_L -> -X'.
  expectNear(lidarToOPrime({0, 1, 0.5}, 90 * kDegToRad, d), {-1, d, 0.5});
  // Z is the rotation axis: heights never change.
  EXPECT_DOUBLE_EQ(lidarToOPrime({0, 0.3, 1.7}, 33 * kDegToRad, d).z(), 1.7);
}

TEST(RotatingGeometry, Eq7MotorAngle) {
  EXPECT_DOUBLE_EQ(motorAngleFromIndex(0, 640, M_PI), 0.0);
  EXPECT_DOUBLE_EQ(motorAngleFromIndex(320, 640, M_PI), M_PI / 2);
  // By time: 16 s for 180 deg (mode 7): after 4 s, 45 deg.
  EXPECT_NEAR(motorAngleFromTime(4000000, 0, M_PI / 16.0), M_PI / 4, 1e-15);
  EXPECT_DOUBLE_EQ(motorAngleFromTime(-1000000, 0, 2.0), -2.0);
}

TEST(RotatingGeometry, Eq8To10Correction) {
  EXPECT_NEAR(phiOffset(30 * kDegToRad, 10 * kDegToRad), 20 * kDegToRad, 1e-15);
  EXPECT_NEAR(phiOffset(170 * kDegToRad, -170 * kDegToRad), -20 * kDegToRad, 1e-12);
  EXPECT_NEAR(wrapAngle(3 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(wrapAngle(-M_PI), M_PI, 1e-12);
  expectNear(oPrimeToO({1, 0, 0.2}, 90 * kDegToRad), {0, 1, 0.2});
}

// A point measured with the shaft at phi_true + phi_motor lands, after Eq. 5 and Eq. 8
// with phi_offset = phi_true, where a perfectly known shaft would have put it.
TEST(RotatingGeometry, CorrectionRecoversTruePoint) {
  const double d = 0.0139, phi_true = 7.5 * kDegToRad, phi_motor = 100 * kDegToRad;
  const Eigen::Vector3d p_L = pointInLidar(3.2, 40 * kDegToRad);
  const Eigen::Vector3d truth = rotZ(phi_true + phi_motor) * (p_L + Eigen::Vector3d(d, 0, 0));
  expectNear(oPrimeToO(lidarToOPrime(p_L, phi_motor, d), phi_true), truth, 1e-12);
}

}  // namespace
}  // namespace rotating
}  // namespace sweepmap
