// Plate-angle calibration (Yuan 2021 Eq. 11-20, Algorithm A1) on synthetic wall normals.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "calib/plate_angle.hpp"
#include "calib/rotating_geometry.hpp"
#include "core/angles.hpp"

namespace sweepmap {
namespace {

const double kAlphaUsed = 30 * kDegToRad;

// The four inward wall normals of an axis-aligned rectangular room, as a sweep assembled
// with plate angle `alpha_used` sees them when the true angle is `alpha_true`:
// C_O(assembled) = R_z(alpha_used - alpha_true) C_O(true). Each normal is tilted by a
// random rotation of `noise_deg` (Gaussian per axis) when `rng` is given.
SweepNormals roomSweep(double alpha_true, double alpha_used, double noise_deg = 0,
                       std::mt19937* rng = nullptr) {
  SweepNormals s;
  s.alpha_used_rad = alpha_used;
  const Eigen::Matrix3d R = rotating::rotZ(alpha_used - alpha_true);
  std::normal_distribution<double> g(0.0, noise_deg * kDegToRad);
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(1, 0, 0),
                                   Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(-1, 0, 0)}) {
    Eigen::Vector3d m = R * n;
    if (rng) {
      const Eigen::Vector3d w(g(*rng), g(*rng), g(*rng));
      m = Eigen::AngleAxisd(w.norm(), w.norm() > 0 ? w.normalized() : Eigen::Vector3d::UnitZ()) * m;
    }
    s.normals.push_back(m.normalized());
  }
  return s;
}

TEST(PlateAngleCost, HandCases) {
  // Walls aligned with the axes: no attitude error.
  SweepNormals aligned = roomSweep(kAlphaUsed, kAlphaUsed);
  EXPECT_NEAR(attitudeError(aligned), 0.0, 1e-15);
  // Rotated by 10 degrees: every term is sin(10 deg).
  SweepNormals rotated = roomSweep(20 * kDegToRad, kAlphaUsed);
  EXPECT_NEAR(attitudeError(rotated), 4 * std::sin(10 * kDegToRad), 1e-12);
  // ...and rotating back by alpha = alpha_true removes it.
  EXPECT_NEAR(fCost(rotated, 20 * kDegToRad), 0.0, 1e-12);
  EXPECT_NEAR(fCost(rotated, 25 * kDegToRad), 4 * std::sin(5 * kDegToRad), 1e-12);
  // Hand case of Eq. 11 with one tilted normal: n = (0.6, 0.8, 0) is nearest +j, so its
  // term is |n . i| = 0.6; n = (-1, 0, 0) contributes |n . j| = 0.
  SweepNormals hand;
  hand.alpha_used_rad = 0;
  hand.normals = {Eigen::Vector3d(0.6, 0.8, 0), Eigen::Vector3d(-1, 0, 0)};
  EXPECT_NEAR(attitudeError(hand), 0.6, 1e-15);
  // Rotating by +90 deg: R n = (-0.8, 0.6, 0), still scored against i (class is fixed).
  EXPECT_NEAR(fCost(hand, 90 * kDegToRad), 0.8 + 1.0, 1e-12);
  // F_cost = 1/2 sum f^2.
  EXPECT_NEAR(totalCost({hand, hand}, 0), 0.6 * 0.6, 1e-15);
}

TEST(PlateAngleCost, DerivativeMatchesCentralDifference) {
  std::mt19937 rng(3);
  const SweepNormals s = roomSweep(29.3598 * kDegToRad, kAlphaUsed, 0.5, &rng);
  for (double a : {25.0, 29.0, 31.0, 35.0}) {
    const double h = 1e-7;
    const double numeric = (fCost(s, a * kDegToRad + h) - fCost(s, a * kDegToRad - h)) / (2 * h);
    EXPECT_NEAR(fCostDerivative(s, a * kDegToRad), numeric, 1e-6) << a;
  }
}

class LmExact : public ::testing::TestWithParam<double> {};

TEST_P(LmExact, RecoversAlphaFromNoiseFreeNormals) {
  const double alpha_true = GetParam() * kDegToRad;
  std::vector<SweepNormals> sweeps(5, roomSweep(alpha_true, kAlphaUsed));
  const LmResult r = calibratePlateAngle(sweeps);
  EXPECT_TRUE(r.converged) << r.stop_reason;
  EXPECT_LT(std::abs(r.alpha_rad - alpha_true) / kDegToRad, 1e-6)
      << "alpha " << r.alpha_rad / kDegToRad << " deg after " << r.iterations << " iterations";
  EXPECT_LT(r.final_cost, 1e-12);
  EXPECT_LE(r.iterations, 500);
}

INSTANTIATE_TEST_SUITE_P(PlateAngleLm, LmExact, ::testing::Values(29.3598, 30.7, 28.0, 30.0, 33.0));

TEST(PlateAngleLm, NoisyNormalsFiftySweeps) {
  std::mt19937 rng(11);
  const double alpha_true = 29.3598 * kDegToRad;
  std::vector<SweepNormals> sweeps;
  for (int m = 0; m < 50; ++m) sweeps.push_back(roomSweep(alpha_true, kAlphaUsed, 0.2, &rng));
  const LmResult r = calibratePlateAngle(sweeps);
  std::cout << "noisy normals: alpha " << r.alpha_rad / kDegToRad << " deg (true 29.3598), "
            << r.iterations << " iterations, " << r.stop_reason << "\n";
  EXPECT_TRUE(r.converged) << r.stop_reason;
  EXPECT_LT(std::abs(r.alpha_rad - alpha_true) / kDegToRad, 0.05);
}

TEST(PlateAngleLm, HistoryStartsAtAlpha0AndNeverIncreases) {
  std::mt19937 rng(5);
  std::vector<SweepNormals> sweeps;
  for (int m = 0; m < 20; ++m) sweeps.push_back(roomSweep(28 * kDegToRad, kAlphaUsed, 0.3, &rng));
  const LmResult r = calibratePlateAngle(sweeps);
  ASSERT_EQ(r.history.size(), static_cast<size_t>(r.iterations) + 1);
  EXPECT_EQ(r.history.front().k, 0);
  EXPECT_DOUBLE_EQ(r.history.front().alpha_rad, 30 * kDegToRad);
  EXPECT_DOUBLE_EQ(r.history.front().cost, totalCost(sweeps, 30 * kDegToRad));
  for (size_t i = 1; i < r.history.size(); ++i) {
    EXPECT_EQ(r.history[i].k, static_cast<int>(i));
    EXPECT_LE(r.history[i].cost, r.history[i - 1].cost) << "iteration " << i;
  }
  EXPECT_DOUBLE_EQ(r.history.back().alpha_rad, r.alpha_rad);
  EXPECT_DOUBLE_EQ(r.final_cost, totalCost(sweeps, r.alpha_rad));
}

TEST(PlateAngleLm, RespectsKMax) {
  std::vector<SweepNormals> sweeps(3, roomSweep(28 * kDegToRad, kAlphaUsed));
  LmOptions o;
  o.k_max = 2;
  o.tau = 1e3;  // heavy damping: tiny steps, so eps2 cannot stop it within 2 iterations
  const LmResult r = calibratePlateAngle(sweeps, o);
  EXPECT_EQ(r.iterations, 2);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.stop_reason, "k_max iterations reached");
  EXPECT_EQ(r.history.size(), 3u);
  o.k_max = 0;
  EXPECT_EQ(calibratePlateAngle(sweeps, o).iterations, 0);
}

TEST(PlateAngleLm, StartsFromAlpha0AndStopsOnZeroGradient) {
  std::vector<SweepNormals> sweeps(3, roomSweep(30 * kDegToRad, kAlphaUsed));
  const LmResult r = calibratePlateAngle(sweeps);  // alpha0 = 30 deg is already exact
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_DOUBLE_EQ(r.alpha_rad, 30 * kDegToRad);
}

TEST(PlateAngleLm, NoSweepsIsNotConverged) {
  const LmResult r = calibratePlateAngle({});
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.stop_reason, "no sweeps");
}

}  // namespace
}  // namespace sweepmap
