#include <gtest/gtest.h>

#include <cmath>

#include "calib/world_assembly.hpp"
#include "core/angles.hpp"

namespace sweepmap {
namespace {

TEST(WorldAssembly, RotationOrderIsZYX) {
  const Eigen::Matrix3d R = rotationXYZ(0.1, 0.2, 0.3);
  const Eigen::Matrix3d want = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()))
                                   .toRotationMatrix();
  EXPECT_TRUE(R.isApprox(want, 1e-15));
  EXPECT_TRUE(rotationXYZ(0, 0, 0).isIdentity(0));
}

// A horizontal lidar: nominal pitch +90 deg maps the sector's middle Z_L to body x.
TEST(WorldAssembly, HorizontalMountingLooksForward) {
  LidarMounting m;
  m.nominal_rpy_rad = Eigen::Vector3d(0, 90 * kDegToRad, 0);
  m.t_BL_m = Eigen::Vector3d(0.145, 0, 0.3);
  const Eigen::Isometry3d T = m.T_BL();
  EXPECT_TRUE((T * Eigen::Vector3d(0, 0, 2)).isApprox(Eigen::Vector3d(2.145, 0, 0.3), 1e-12));
  EXPECT_TRUE((T * Eigen::Vector3d(0, 1, 0)).isApprox(Eigen::Vector3d(0.145, 1, 0.3), 1e-12));
}

TEST(PoseTrack, InterpolatesAndWrapsHeading) {
  PoseTrack t;
  t.add(0, {0, 0, 170 * kDegToRad});
  t.add(1000, {1, 2, -170 * kDegToRad});
  const auto mid = t.at(500);
  ASSERT_TRUE(mid);
  EXPECT_DOUBLE_EQ(mid->x_m, 0.5);
  EXPECT_DOUBLE_EQ(mid->y_m, 1.0);
  EXPECT_NEAR(std::remainder(mid->theta_rad - M_PI, 2 * M_PI), 0.0, 1e-12);  // through 180 deg
  EXPECT_FALSE(t.at(-1));
  EXPECT_FALSE(t.at(1001));
  EXPECT_TRUE(t.at(1000));
  t.pruneBefore(700);
  EXPECT_EQ(t.size(), 2u);  // the pose before 700 stays for interpolation
  EXPECT_TRUE(t.at(700));
}

// The robot drives at 1 m/s toward a wall 5 m ahead while a 10 Hz scan sweeps: with each
// ray's own pose the wall is straight at x = 5; with the scan's start pose it smears.
TEST(WorldAssembly, DeskewsWithEachRaysPose) {
  LidarMounting m;
  m.nominal_rpy_rad = Eigen::Vector3d(0, 90 * kDegToRad, 0);
  PoseTrack track;
  for (int64_t t = 0; t <= 200000; t += 10000) track.add(t, {1e-6 * double(t), 0, 0});
  Scan2D s;
  s.utime = 0;
  s.angle_min_rad = -30 * kDegToRad;
  s.angle_increment_rad = 1 * kDegToRad;
  s.time_increment_ns = 1000000;  // 1 ms per ray: 61 ms for the scan
  s.range_min_m = 0.02;
  s.range_max_m = 10;
  for (int i = 0; i <= 60; ++i) {
    const double a = s.rayAngle(static_cast<size_t>(i));
    const double x_robot = 1e-3 * i;  // where the robot is at this ray
    s.ranges_m.push_back(static_cast<float>((5.0 - x_robot) / std::cos(a)));
  }
  int uncovered = -1;
  const auto pts = scanToWorld(s, track, m.T_BL(), &uncovered);
  ASSERT_EQ(pts.size(), 61u);
  EXPECT_EQ(uncovered, 0);
  for (const auto& p : pts) EXPECT_NEAR(p.x(), 5.0, 1e-5);
  // Without deskewing (every ray at the scan's start pose) the last ray is 6 cm short.
  PoseTrack frozen;
  frozen.add(0, {0, 0, 0});
  frozen.add(1000000, {0, 0, 0});
  EXPECT_NEAR(scanToWorld(s, frozen, m.T_BL()).back().x(), 5.0 - 0.06, 1e-4);
}

// A robot standing still at the origin for 5 ms, and a scan of n_rays returns at 1 m, 1 ms
// apart from t = 0: rays 0-5 have a pose, the later ones fall after the track's end.
struct StillTrackAndScan {
  PoseTrack track;
  Scan2D scan;
};

StillTrackAndScan stillTrackAndScan(size_t n_rays) {
  StillTrackAndScan r;
  r.track.add(0, {0, 0, 0});
  r.track.add(5000, {0, 0, 0});
  r.scan.time_increment_ns = 1000000;
  r.scan.range_min_m = 0.02;
  r.scan.range_max_m = 10;
  r.scan.angle_increment_rad = 0.01;
  r.scan.ranges_m.assign(n_rays, 1.0f);
  return r;
}

// The intensity of each returned point is its own ray's; a scan without intensities gives
// none.
TEST(WorldAssembly, PointsKeepTheirRaysIntensity) {
  auto [track, s] = stillTrackAndScan(8);
  s.ranges_m[1] = 0.0f;                                      // ray 1: no return
  s.intensities = {100, 101, 102, 103, 104, 105, 106, 107};  // rays 6, 7: no pose
  std::vector<float> intensities = {-1};
  const auto pts = scanToWorld(s, track, Eigen::Isometry3d::Identity(), nullptr, &intensities);
  ASSERT_EQ(pts.size(), 5u);
  EXPECT_EQ(intensities, (std::vector<float>{100, 102, 103, 104, 105}));
  s.intensities.clear();
  scanToWorld(s, track, Eigen::Isometry3d::Identity(), nullptr, &intensities);
  EXPECT_TRUE(intensities.empty());
}

TEST(WorldAssembly, RaysOutsideTheTrackAreSkippedAndCounted) {
  const auto [track, s] = stillTrackAndScan(10);
  int uncovered = 0;
  EXPECT_EQ(scanToWorld(s, track, Eigen::Isometry3d::Identity(), &uncovered).size(), 6u);
  EXPECT_EQ(uncovered, 4);
}

}  // namespace
}  // namespace sweepmap
