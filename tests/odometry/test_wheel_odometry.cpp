#include <gtest/gtest.h>

#include "odometry/wheel_odometry.hpp"

namespace sweepmap {
namespace {

TEST(WheelOdometry, TwistFromWheels) {
  const BodyTwist t = twistFromWheels(0.1, 0.3, 0.2);
  EXPECT_DOUBLE_EQ(t.v_m_s, 0.2);
  EXPECT_DOUBLE_EQ(t.w_rad_s, 1.0);
  EXPECT_DOUBLE_EQ(twistFromWheels(-0.5, 0.5, 0.25).v_m_s, 0.0);
}

TEST(WheelOdometry, Eq2To5StraightAndTurnInPlace) {
  Pose2 p;
  p = integrateOdometry(p, {0.5, 0.0}, 2.0);
  EXPECT_DOUBLE_EQ(p.x_m, 1.0);
  EXPECT_DOUBLE_EQ(p.y_m, 0.0);
  p = integrateOdometry(p, {0.0, M_PI / 2}, 1.0);
  EXPECT_DOUBLE_EQ(p.theta_rad, M_PI / 2);
  p = integrateOdometry(p, {1.0, 0.0}, 1.0);  // heading +Y now
  EXPECT_NEAR(p.x_m, 1.0, 1e-12);
  EXPECT_NEAR(p.y_m, 1.0, 1e-12);
}

// Small steps along a circle of radius 0.83 m (the paper's calibration drive) close it.
TEST(WheelOdometry, CircleCloses) {
  const double r = 0.83, v = 0.2, w = v / r, dt = 0.001;
  Pose2 p;
  const int steps = static_cast<int>(std::round(2 * M_PI / w / dt));
  for (int i = 0; i < steps; ++i) p = integrateOdometry(p, {v, w}, dt);
  EXPECT_NEAR(p.x_m, 0.0, 2e-3);
  EXPECT_NEAR(p.y_m, 0.0, 2e-3);
}

TEST(WheelOdometry, TicksToSpeed) {
  // 2000 ticks per revolution (BreezySLAM's robot), r = 0.077 m: 1000 ticks in 1 s = half a turn.
  EXPECT_NEAR(wheelSpeedFromTicks(1000, 1.0, 2000, 0.077), M_PI * 0.077, 1e-12);
}

}  // namespace
}  // namespace sweepmap
