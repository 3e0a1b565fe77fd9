#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "calib/plate.hpp"
#include "calib/rotating_geometry.hpp"

namespace sweepmap {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Points on the paper's plate (isosceles right triangle, hypotenuse 112 mm at 54.75 mm
// from the axis) at height z, middle line at `beta` in O', sampled the way a rotating
// scan plane samples it: `rings` radial steps x `spokes` angular steps over the plate.
std::vector<Eigen::Vector3f> synthPlate(double beta, int spokes, int rings, double z,
                                        double noise_m = 0.0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_m > 0 ? noise_m : 1.0);
  std::vector<Eigen::Vector3f> pts;
  const double base = 0.05475, half = 0.056;
  for (int s = 0; s < spokes; ++s) {
    const double v = -half + 2 * half * (s + 0.5) / spokes;  // across the middle line
    for (int r = 0; r < rings; ++r) {
      const double u = base + (half - std::abs(v)) * (r + 0.5) / rings;  // outward
      Eigen::Vector3d p(u, v, z);
      if (noise_m > 0) p += Eigen::Vector3d(n(rng), n(rng), n(rng));
      pts.push_back((rotating::rotZ(beta) * p).cast<float>());
    }
  }
  return pts;
}

PlateRegion paperRegion() {
  PlateConfig c;  // defaults: the paper's semi-ring
  return PlateRegion::fromConfig(c);
}

TEST(PlateRegion, SemiRingBounds) {
  const PlateRegion r = paperRegion();
  EXPECT_TRUE(r.contains({0.09f, 0.0f, -0.045f}));
  EXPECT_FALSE(r.contains({-0.09f, 0.0f, -0.045f}));   // other half
  EXPECT_FALSE(r.contains({0.05f, 0.0f, -0.045f}));    // inside inner radius
  EXPECT_FALSE(r.contains({0.12f, 0.0f, -0.045f}));    // beyond outer radius
  EXPECT_FALSE(r.contains({0.09f, 0.0f, -0.030f}));    // above the slab (+-10 mm)
  EXPECT_TRUE(r.contains({0.0f, 0.09f, -0.054f}));     // on the cut, inside the slab
}

class CentroidAtDensity : public ::testing::TestWithParam<int> {};

TEST_P(CentroidAtDensity, RecoversBetaOfSymmetricPlate) {
  const int spokes = GetParam();
  for (double beta_deg : {-20.0, 0.0, 12.5, 35.0}) {
    const auto pts = synthPlate(beta_deg * kDeg, spokes, 12, -0.045);
    const PlateEstimate e = estimateBetaCentroid(pts, paperRegion(), 30);
    ASSERT_TRUE(e.found) << e.reason;
    EXPECT_NEAR(e.beta_rad / kDeg, beta_deg, 1e-3) << "spokes " << spokes;
  }
}

INSTANTIATE_TEST_SUITE_P(Densities, CentroidAtDensity, ::testing::Values(8, 20, 80, 400));

TEST(Centroid, NoiseAveragesOut) {
  const auto pts = synthPlate(10 * kDeg, 200, 20, -0.045, 0.004, 7);
  const PlateEstimate e = estimateBetaCentroid(pts, paperRegion(), 30);
  ASSERT_TRUE(e.found);
  EXPECT_NEAR(e.beta_rad / kDeg, 10.0, 0.3);
}

TEST(Centroid, TooFewPointsIsNotFound) {
  const auto pts = synthPlate(0.0, 2, 5, -0.045);  // 10 points
  const PlateEstimate e = estimateBetaCentroid(pts, paperRegion(), 30);
  EXPECT_FALSE(e.found);
  EXPECT_EQ(e.points, 10);
  EXPECT_NE(e.reason.find("10 points"), std::string::npos);
}

TEST(Centroid, PointsOutsideRegionIgnored) {
  auto pts = synthPlate(5 * kDeg, 40, 10, -0.045);
  const PlateEstimate clean = estimateBetaCentroid(pts, paperRegion(), 30);
  pts.push_back({-0.09f, 0.0f, -0.045f});  // other half
  pts.push_back({2.0f, 1.0f, -0.045f});    // far away
  pts.push_back({0.09f, 0.0f, 0.5f});      // above
  const PlateEstimate e = estimateBetaCentroid(pts, paperRegion(), 30);
  EXPECT_EQ(e.points, clean.points);
  EXPECT_NEAR(e.beta_rad / kDeg, 5.0, 1e-3);
  EXPECT_EQ(extractPlatePoints(pts, paperRegion()).size(), static_cast<size_t>(e.points));
}

}  // namespace
}  // namespace sweepmap
