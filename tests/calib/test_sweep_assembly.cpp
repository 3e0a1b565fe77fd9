#include <gtest/gtest.h>

#include <cmath>

#include "calib/rotating_geometry.hpp"
#include "calib/sweep_assembly.hpp"
#include "core/angles.hpp"

namespace sweepmap {
namespace {

class SweepAssemblyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    rig_.lidar.beam_count = 5;
    window_.sweep_id = 3;
    window_.mode = 1;
    window_.start_utime = 1000000;
    window_.end_utime = 2000000;
    window_.omega_rad_s = M_PI;  // 180 deg in 1 s
  }
  Scan2D scan(int j, float range) const {
    Scan2D s;
    s.utime = window_.start_utime + 25000 * j;
    s.seq = j;
    s.angle_min_rad = -90 * kDegToRad;
    s.angle_increment_rad = 45 * kDegToRad;
    s.time_increment_ns = 1000000;  // 1 ms between rays
    s.range_min_m = 0.06;
    s.range_max_m = 10.0;
    s.ranges_m.assign(5, range);
    return s;
  }
  RotatingLidarConfig rig_;
  SweepWindow window_;
};

TEST_F(SweepAssemblyTest, PointsUseEachRaysOwnTime) {
  const std::vector<Scan2D> scans = {scan(0, 2.0f), scan(4, 2.0f)};
  const AssembledSweep s = assembleSweep(scans, window_, rig_);
  ASSERT_EQ(s.points_Op.size(), 10u);
  EXPECT_EQ(s.first_ray_utime, window_.start_utime);
  const double d = rig_.geometry.lidar_offset_x_mm * 1e-3;
  // Scan 4, ray 2 (theta = 0): time 0.1 s + 2 ms after the first ray.
  const double phi = M_PI * (0.1 + 0.002);
  const Eigen::Vector3d want = rotating::lidarToOPrime(rotating::pointInLidar(2.0, 0.0), phi, d);
  EXPECT_LT((s.points_Op[7].cast<double>() - want).norm(), 1e-6);
}

// A scan of part of the field of view (a SCIP sub-range: rays 1..3 of the 5, its first ray
// 1 ms later, each ray at its own angle) gives the same points as those rays of the full scan:
// the assembler takes each ray's angle and time from the scan, not from the rig's grid.
TEST_F(SweepAssemblyTest, ASubRangeScanGivesTheSameRaysPoints) {
  Scan2D full = scan(4, 0.0f);
  for (size_t i = 0; i < 5; ++i) full.ranges_m[i] = 1.0f + 0.25f * float(i);
  Scan2D part = full;
  part.ranges_m.assign(full.ranges_m.begin() + 1, full.ranges_m.begin() + 4);
  part.angle_min_rad = full.rayAngle(1);
  part.utime = full.rayUtime(1);
  // The sweep's first scan (its first ray: phi = 0) is the same full scan in both.
  const AssembledSweep a = assembleSweep({scan(0, 2.0f), full}, window_, rig_);
  const AssembledSweep b = assembleSweep({scan(0, 2.0f), part}, window_, rig_);
  ASSERT_EQ(a.points_Op.size(), 10u);
  ASSERT_EQ(b.points_Op.size(), 8u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_LT((b.points_Op[5 + i] - a.points_Op[5 + 1 + i]).norm(), 1e-6) << i;
  }
}

TEST_F(SweepAssemblyTest, SkipsNoReturnAndOutOfLimitRays) {
  Scan2D a = scan(0, 2.0f);
  a.ranges_m[0] = 0.0f;   // no return
  a.ranges_m[1] = 0.01f;  // below range_min
  a.ranges_m[2] = 12.0f;  // beyond range_max
  const AssembledSweep s = assembleSweep({a}, window_, rig_);
  EXPECT_EQ(s.points_Op.size(), 2u);
}

// Each point keeps its own ray's intensity, skipped rays and all, through the correction;
// one scan of the window without intensities leaves the sweep without them.
TEST_F(SweepAssemblyTest, EachPointCarriesItsRaysIntensity) {
  Scan2D a = scan(0, 2.0f), b = scan(4, 2.0f);
  a.intensities = {10.0f, 11.0f, 12.0f, 13.0f, 14.0f};
  b.intensities = {20.0f, 21.0f, 22.0f, 23.0f, 24.0f};
  a.ranges_m[1] = 0.0f;   // no return: its point and its intensity go
  b.ranges_m[4] = 12.0f;  // beyond range_max
  const AssembledSweep s = assembleSweep({a, b}, window_, rig_);
  ASSERT_EQ(s.points.size(), 8u);
  EXPECT_EQ(s.intensities, (std::vector<float>{10, 12, 13, 14, 20, 21, 22, 23}));
  AssembledSweep corrected = s;
  uncorrectSweep("test", &corrected);
  EXPECT_EQ(corrected.intensities.size(), corrected.points.size());
  b.intensities.clear();  // a lidar (or a scan) without intensity
  EXPECT_TRUE(assembleSweep({a, b}, window_, rig_).intensities.empty());
}

TEST_F(SweepAssemblyTest, NoPlateMeansUncorrectedWithReason) {
  const AssembledSweep s = assembleSweep({scan(0, 2.0f)}, window_, rig_);
  EXPECT_FALSE(s.corrected);
  EXPECT_EQ(s.phi_offset_rad, 0.0);
  EXPECT_NE(s.reason.find("plate not found"), std::string::npos);
  EXPECT_EQ(s.points, s.points_Op);
}

TEST_F(SweepAssemblyTest, EmptyWindow) {
  const AssembledSweep s = assembleSweep({}, window_, rig_);
  EXPECT_FALSE(s.corrected);
  EXPECT_EQ(s.reason, "no scans in the window");
}

// Plate points put straight into a sweep: the correction rotates by alpha - beta.
TEST_F(SweepAssemblyTest, CorrectionAppliesAlphaMinusBeta) {
  // A scan whose rays, at their times, hit the plate region: place rays by inverting Eq. 4-5
  // is awkward, so use a stationary shaft (omega ~ 0) and one ray straight down-out.
  window_.omega_rad_s = 1e-9;
  rig_.plate.min_points = 1;
  Scan2D s = scan(0, 0.0f);
  // theta such that the point lies at x = 0.0139 + 0, y = r sin(theta), z = r cos(theta):
  // choose y = 0.08, z = -0.045.
  const double y = 0.08, z = -0.045;
  s.angle_min_rad = std::atan2(y, z);
  s.angle_increment_rad = 0.0;
  s.ranges_m.assign(5, static_cast<float>(std::hypot(y, z)));
  const AssembledSweep out = assembleSweep({s}, window_, rig_);
  ASSERT_TRUE(out.corrected) << out.reason;
  const double beta = std::atan2(y, rig_.geometry.lidar_offset_x_mm * 1e-3);
  EXPECT_NEAR(out.plate.beta_rad, beta, 1e-6);
  EXPECT_NEAR(out.phi_offset_rad, wrapAngle(30 * kDegToRad - beta), 1e-6);
  const Eigen::Vector3f rotated =
      (rotating::rotZ(out.phi_offset_rad) * out.points_Op[0].cast<double>()).cast<float>();
  EXPECT_LT((out.points[0] - rotated).norm(), 1e-6);
}

TEST_F(SweepAssemblyTest, RampOverlapOrDisabledCorrectionLeavesUncorrected) {
  window_.accel_overlap = true;
  EXPECT_NE(assembleSweep({scan(0, 2.0f)}, window_, rig_).reason.find("ramp"), std::string::npos);
  window_.accel_overlap = false;
  rig_.assembler.correct_attitude = false;
  EXPECT_NE(assembleSweep({scan(0, 2.0f)}, window_, rig_).reason.find("disabled"),
            std::string::npos);
}

}  // namespace
}  // namespace sweepmap
