#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <random>

#include "calib/plate.hpp"
#include "calib/plate_model.hpp"
#include "calib/rotating_geometry.hpp"
#include "core/angles.hpp"

namespace sweepmap {
namespace {

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
  EXPECT_FALSE(r.contains({-0.09f, 0.0f, -0.045f}));  // other half
  EXPECT_FALSE(r.contains({0.05f, 0.0f, -0.045f}));   // inside inner radius
  EXPECT_FALSE(r.contains({0.12f, 0.0f, -0.045f}));   // beyond outer radius
  EXPECT_FALSE(r.contains({0.09f, 0.0f, -0.030f}));   // above the slab (+-10 mm)
  EXPECT_TRUE(r.contains({0.0f, 0.09f, -0.054f}));    // on the cut, inside the slab
}

class CentroidAtDensity : public ::testing::TestWithParam<int> {};

TEST_P(CentroidAtDensity, RecoversBetaOfSymmetricPlate) {
  const int spokes = GetParam();
  for (double beta_deg : {-20.0, 0.0, 12.5, 35.0}) {
    const auto pts = synthPlate(beta_deg * kDegToRad, spokes, 12, -0.045);
    const PlateEstimate e = estimateBetaCentroid(pts, paperRegion(), 30);
    ASSERT_TRUE(e.found) << e.reason;
    EXPECT_NEAR(e.beta_rad / kDegToRad, beta_deg, 1e-3) << "spokes " << spokes;
  }
}

INSTANTIATE_TEST_SUITE_P(Densities, CentroidAtDensity, ::testing::Values(8, 20, 80, 400));

TEST(Centroid, NoiseAveragesOut) {
  const auto pts = synthPlate(10 * kDegToRad, 200, 20, -0.045, 0.004, 7);
  const PlateEstimate e = estimateBetaCentroid(pts, paperRegion(), 30);
  ASSERT_TRUE(e.found);
  EXPECT_NEAR(e.beta_rad / kDegToRad, 10.0, 0.3);
}

TEST(Centroid, TooFewPointsIsNotFound) {
  const auto pts = synthPlate(0.0, 2, 5, -0.045);  // 10 points
  const PlateEstimate e = estimateBetaCentroid(pts, paperRegion(), 30);
  EXPECT_FALSE(e.found);
  EXPECT_EQ(e.points, 10);
  EXPECT_NE(e.reason.find("10 points"), std::string::npos);
}

TEST(Centroid, PointsOutsideRegionIgnored) {
  auto pts = synthPlate(5 * kDegToRad, 40, 10, -0.045);
  const PlateEstimate clean = estimateBetaCentroid(pts, paperRegion(), 30);
  pts.push_back({-0.09f, 0.0f, -0.045f});  // other half
  pts.push_back({2.0f, 1.0f, -0.045f});    // far away
  pts.push_back({0.09f, 0.0f, 0.5f});      // above
  const PlateEstimate e = estimateBetaCentroid(pts, paperRegion(), 30);
  EXPECT_EQ(e.points, clean.points);
  EXPECT_NEAR(e.beta_rad / kDegToRad, 5.0, 1e-3);
  EXPECT_EQ(extractPlatePoints(pts, paperRegion()).size(), static_cast<size_t>(e.points));
}

// Rays of a rotating scan plane (13.9 mm off the axis, as rig A) over a plate lying at
// z = -45 mm with its middle line at `beta`; noisy ranges along the rays.
struct RayScan {
  std::vector<PlateRay> rays;
  std::vector<Eigen::Vector3f> points;
};

bool insidePlate(const Eigen::Vector2d& p, double beta) {
  const Eigen::Vector2d q = rotating::rotZ(-beta).topLeftCorner<2, 2>() * p;  // plate frame
  const double base = 0.05475, half = 0.056;
  return q.x() >= base && std::abs(q.y()) <= half - (q.x() - base);
}

RayScan scanPlate(double beta, double phi_step_deg, double noise_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_m);
  RayScan out;
  const double d = 0.0139, z = -0.045;
  for (double phi = 0; phi < 180; phi += phi_step_deg) {
    const Eigen::Matrix3d R = rotating::rotZ(phi * kDegToRad);
    for (double theta = -135; theta <= 135; theta += 0.25) {
      const Eigen::Vector3d origin = R * Eigen::Vector3d(d, 0, 0);
      const Eigen::Vector3d dir =
          R * Eigen::Vector3d(0, std::sin(theta * kDegToRad), std::cos(theta * kDegToRad));
      if (dir.z() >= 0) continue;
      const double t = z / dir.z();
      if (!insidePlate((origin + t * dir).head<2>(), beta)) continue;
      const double r = t + (noise_m > 0 ? n(rng) : 0.0);
      out.rays.push_back({origin, dir, r});
      out.points.push_back((origin + r * dir).cast<float>());
    }
  }
  return out;
}

TEST(RayPlane, NoiseFreeAgreesWithCentroid) {
  const RayScan s = scanPlate(25 * kDegToRad, 0.28125, 0.0, 1);
  const PlateEstimate c = estimateBetaCentroid(s.points, paperRegion(), 30);
  const PlateEstimate r = estimateBetaRayPlane(s.rays, paperRegion(), 0.03, 30);
  ASSERT_TRUE(c.found && r.found);
  EXPECT_NEAR(r.beta_rad / kDegToRad, 25.0, 0.02);
  EXPECT_NEAR(c.beta_rad / kDegToRad, 25.0, 0.02);
}

// With UST-10LX-like noise the centroid of noisy points is biased (points near the
// region's edges are kept or dropped depending on their noise); the ray-plane estimate
// is not. Several seeds, mode-7 density.
TEST(RayPlane, UnbiasedUnderRangeNoiseWhereCentroidIsNot) {
  double mean_centroid = 0, mean_rays = 0;
  const int runs = 6;
  for (int k = 0; k < runs; ++k) {
    const RayScan s = scanPlate(25 * kDegToRad, 0.28125, 0.012, 100 + k);
    mean_centroid += estimateBetaCentroid(s.points, paperRegion(), 30).beta_rad / kDegToRad - 25.0;
    mean_rays += estimateBetaRayPlane(s.rays, paperRegion(), 0.03, 30).beta_rad / kDegToRad - 25.0;
  }
  mean_centroid /= runs;
  mean_rays /= runs;
  std::cout << "mean beta error: centroid " << mean_centroid << " deg, ray-plane " << mean_rays
            << " deg\n";
  EXPECT_LT(std::abs(mean_rays), 0.05);
  EXPECT_GT(std::abs(mean_centroid), 2 * std::abs(mean_rays));
}

// Both methods at the angular steps of modes 1, 3, 5 and 7 (4.5 .. 0.28125 deg), noisy.
class BothMethodsAtDensity : public ::testing::TestWithParam<double> {};

TEST_P(BothMethodsAtDensity, EstimateBeta) {
  const double step_deg = GetParam();
  const RayScan s = scanPlate(-12 * kDegToRad, step_deg, 0.012, 9);
  const PlateEstimate c = estimateBetaCentroid(s.points, paperRegion(), 30);
  const PlateEstimate r = estimateBetaRayPlane(s.rays, paperRegion(), 0.03, 30);
  ASSERT_TRUE(c.found && r.found) << c.reason << r.reason;
  std::cout << "step " << step_deg << " deg: centroid " << c.beta_rad / kDegToRad + 12
            << " deg, ray-plane " << r.beta_rad / kDegToRad + 12 << " deg off\n";
  // Sparse scans sample the plate coarsely: both errors grow with the step.
  const double bound = std::max(0.15, 0.25 * step_deg);
  EXPECT_NEAR(r.beta_rad / kDegToRad, -12.0, bound);
  EXPECT_NEAR(c.beta_rad / kDegToRad, -12.0, bound + 0.4);
}

INSTANTIATE_TEST_SUITE_P(Modes1357, BothMethodsAtDensity,
                         ::testing::Values(4.5, 1.125, 0.5625, 0.28125));

TEST(RayPlane, GateRejectsRaysThatHitSomethingElse) {
  RayScan s = scanPlate(0.0, 1.0, 0.0, 1);
  const size_t n = s.rays.size();
  for (size_t i = 0; i < n; i += 2) s.rays[i].range_m += 0.5;  // an object above the plate
  const PlateEstimate r = estimateBetaRayPlane(s.rays, paperRegion(), 0.03, 30);
  ASSERT_TRUE(r.found);
  EXPECT_LE(r.points, static_cast<int>((n + 1) / 2));
  EXPECT_NEAR(r.beta_rad, 0.0, 0.5 * kDegToRad);
  EXPECT_FALSE(estimateBetaRayPlane({}, paperRegion(), 0.03, 30).found);
}

class PlateCheckTest : public ::testing::Test {
 protected:
  PlateCheck check(const RayScan& s, double beta) const {
    return checkPlate(s.rays, paperRegion(), beta, 0.112, 0.05475, 0.03);
  }
  // Every ray that meets the plate plane in the region (not only those on the plate).
  RayScan regionRays(double beta, double noise_m) const {
    RayScan out;
    std::mt19937 rng(5);
    std::normal_distribution<double> n(0.0, noise_m);
    for (double phi = 0; phi < 180; phi += 0.5625) {
      const Eigen::Matrix3d R = rotating::rotZ(phi * kDegToRad);
      for (double theta = -135; theta <= 135; theta += 0.25) {
        const Eigen::Vector3d origin = R * Eigen::Vector3d(0.0139, 0, 0);
        const Eigen::Vector3d dir =
            R * Eigen::Vector3d(0, std::sin(theta * kDegToRad), std::cos(theta * kDegToRad));
        const auto t = plateRayRange(origin, dir, paperRegion());
        if (!t) continue;
        // Off the plate the ray goes on to the floor, a metre further.
        const bool on = insidePlate((origin + *t * dir).head<2>(), beta);
        out.rays.push_back({origin, dir, (on ? *t : *t + 1.0) + n(rng)});
      }
    }
    return out;
  }
};

TEST_F(PlateCheckTest, CleanPlatePasses) {
  const RayScan s = regionRays(20 * kDegToRad, 0.012);
  const PlateCheck c = check(s, 20 * kDegToRad);
  EXPECT_EQ(c.problem, "") << c.expected << " " << c.on_plate << " " << c.off_plate;
  EXPECT_GT(c.expected, 100);
}

TEST_F(PlateCheckTest, ObjectOverThePlateIsMixed) {
  RayScan s = regionRays(20 * kDegToRad, 0.0);
  for (size_t i = 0; i < s.rays.size(); i += 4) s.rays[i].range_m -= 0.04;  // a cable above
  EXPECT_NE(check(s, 20 * kDegToRad).problem.find("mixed"), std::string::npos);
}

TEST_F(PlateCheckTest, MissingHalfIsPartial) {
  RayScan s = regionRays(20 * kDegToRad, 0.0);
  for (auto& r : s.rays) {
    const Eigen::Vector3d p = r.origin + r.range_m * r.direction;
    if (std::atan2(p.y(), p.x()) > 20 * kDegToRad) r.range_m += 1.0;  // that half is gone
  }
  EXPECT_NE(check(s, 20 * kDegToRad).problem.find("partial"), std::string::npos);
}

TEST_F(PlateCheckTest, WrongBetaDisagreesWithExtent) {
  const RayScan s = regionRays(20 * kDegToRad, 0.0);
  EXPECT_NE(check(s, 35 * kDegToRad).problem, "");
}

// The rays of one full turn as rig A's UST-10LX casts them (scans 0.5625 deg apart, rays 0.25
// deg apart, 13.9 mm off the axis, scan plane tilted 0.3 deg, mirror 0.2 deg) that cross the
// plate's plane in the region, each with the range of a sharp plate at `alpha` (its upper
// surface or its hypotenuse's face; 1 m past it).
std::vector<PlateRay> fullTurnPlateRays(const PlateModel& m, const PlateRegion& region,
                                        double alpha) {
  const Eigen::Matrix3d R_L = rotating::lidarRotation(0.3 * kDegToRad, 0.2 * kDegToRad);
  std::vector<PlateRay> rays;
  for (int k = 0; k < 640; ++k) {
    const Eigen::Matrix3d Rz = rotating::rotZ(k * 0.5625 * kDegToRad);
    for (int i = 0; i < 1081; ++i) {
      const Eigen::Vector3d o = Rz * Eigen::Vector3d(0.0139, 0, 0);
      const Eigen::Vector3d d =
          Rz * R_L * rotating::pointInLidar(1.0, (-135 + 0.25 * i) * kDegToRad);
      const auto t = plateRayRange(o, d, region);
      if (!t) continue;
      rays.push_back({o, d, plateCovers(m, o, d, alpha) ? *t : *t + 1.0});
    }
  }
  return rays;
}

// A sweep's rays are one fixed grid: the smooth edge's prediction misses its centroid by the
// grid's sampling of the edges (0.007-0.016 deg on these four, up to 0.025 deg on the
// simulator's sweeps); with sharp edges
// the model's hits at the true angle are the measured ones, and the fit finds it to the
// grid's resolution.
TEST(PlateModel, SampledFitFindsTheAngleOnAFullTurnsRayGrid) {
  PlateConfig c;
  const PlateModel m = PlateModel::fromConfig(c);
  const PlateRegion region = PlateRegion::fromConfig(c);
  for (const double alpha_deg : {29.3598, 30.1, 31.77, -12.3}) {
    SCOPED_TRACE(alpha_deg);
    const auto rays = fullTurnPlateRays(m, region, alpha_deg * kDegToRad);
    const auto hit = plateHits(m, rays);
    const std::vector<double> hits(hit.begin(), hit.end());
    const PlateModelFit smooth = fitPlateModel(m, rays, 30);
    ASSERT_TRUE(smooth.found);
    EXPECT_NEAR(smooth.angle_rad / kDegToRad, alpha_deg, 0.05);  // the start
    const auto sampled = fitPlateSampled(m, rays, hits, smooth.angle_rad);
    ASSERT_TRUE(sampled.has_value());
    EXPECT_NEAR(*sampled / kDegToRad, alpha_deg, 0.002);
    EXPECT_EQ(*plateSampledMismatch(m, rays, alpha_deg * kDegToRad, hits), 0.0);
  }
}

TEST(PlateModel, SampledFitWithoutAHitIsNotFound) {
  PlateConfig c;
  const PlateModel m = PlateModel::fromConfig(c);
  const auto rays = fullTurnPlateRays(m, PlateRegion::fromConfig(c), 0.5);
  EXPECT_FALSE(fitPlateSampled(m, rays, std::vector<double>(rays.size(), 0.0), 0.5).has_value());
}

// A full turn's scans (as fullTurnPlateRays) with the simulator's mixed pixels
// (sim/artefacts.hpp): a ray whose neighbour's range differs by more than 50 mm takes, with
// probability 0.5, a range uniformly between the two. The rays that cross the plate's plane in
// the region, with their neighbours along the scan.
struct MixedTurn {
  std::vector<PlateRay> rays;
  std::vector<PlateRayBeams> beams;
};

// The background behind the plate: 1 m past the plate's plane along each ray, or (`floor`) the
// floor 1 m below the lidar, whose range climbs along a scan by tens of millimetres a beam where
// the rays graze it. `noise_m`: the ranges' Gaussian noise.
MixedTurn mixedFullTurn(const PlateModel& m, const PlateRegion& region, double alpha, uint64_t seed,
                        bool floor = false, double noise_m = 0.0) {
  const Eigen::Matrix3d R_L = rotating::lidarRotation(0.3 * kDegToRad, 0.2 * kDegToRad);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  MixedTurn turn;
  for (int k = 0; k < 640; ++k) {
    const Eigen::Matrix3d Rz = rotating::rotZ(k * 0.5625 * kDegToRad);
    const Eigen::Vector3d o = Rz * Eigen::Vector3d(0.0139, 0, 0);
    std::vector<Eigen::Vector3d> dirs;
    std::vector<double> range;  // the plate's, or 1 m past the plate's plane (the floor)
    for (int i = 0; i < 1081; ++i) {
      dirs.push_back(Rz * R_L * rotating::pointInLidar(1.0, (-135 + 0.25 * i) * kDegToRad));
      const double t = dirs.back().z() < -1e-3 ? (m.height_m - o.z()) / dirs.back().z() : 3.0;
      const double background = floor && dirs.back().z() < -1e-3 ? -1.0 / dirs.back().z() : t + 1.0;
      range.push_back(plateCovers(m, o, dirs.back(), alpha) ? t : background);
    }
    std::vector<double> mixed = range;
    std::normal_distribution<double> noise(0.0, noise_m > 0.0 ? noise_m : 1.0);
    for (size_t i = 0; noise_m > 0.0 && i < range.size(); ++i) mixed[i] += noise(rng);
    for (size_t i = 1; i + 1 < range.size(); ++i) {
      for (const size_t j : {i - 1, i + 1}) {
        if (std::fabs(range[j] - range[i]) > 0.05 && u(rng) < 0.5) {
          mixed[i] = range[i] + u(rng) * (range[j] - range[i]);
          break;
        }
      }
    }
    std::vector<int> index(range.size(), -1);
    for (size_t i = 0; i < range.size(); ++i) {
      if (!plateRayRange(o, dirs[i], region)) continue;
      index[i] = int(turn.rays.size());
      turn.rays.push_back({o, dirs[i], mixed[i]});
    }
    for (size_t i = 0; i < range.size(); ++i) {
      if (index[i] < 0) continue;
      PlateRayBeams b;
      for (int side = 0; side < 2; ++side) {
        const long j = long(i) + (side ? 1 : -1);
        if (j < 0 || j >= long(range.size())) continue;
        b.range[size_t(side)] = float(mixed[size_t(j)]);
        b.next[size_t(side)] = index[size_t(j)];
      }
      turn.beams.push_back(b);
    }
  }
  return turn;
}

// Mixed pixels at the plate's edges take ~half of its edge rays out of the range gate at
// random (~200 per full turn), always on the plate's side: the hits alone then differ from the
// rays the plate covers at its true angle by those. plateHitWeights leaves the ray past each end
// of a run of hits (the plate's last ray or the background's first) out of both centroids.
TEST(PlateModel, MixedPixelsAtThePlatesEdgesAreCountedOrLeftOut) {
  PlateConfig c;
  const PlateModel m = PlateModel::fromConfig(c);
  const PlateRegion region = PlateRegion::fromConfig(c);
  const double alpha = 29.3598 * kDegToRad;
  for (const uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(seed);
    const MixedTurn t = mixedFullTurn(m, region, alpha, seed);
    const auto hits = plateHits(m, t.rays);
    const auto w = plateHitWeights(m, t.rays, t.beams);
    int by_hits = 0, by_weights = 0;
    for (size_t i = 0; i < t.rays.size(); ++i) {
      const bool covered = plateCovers(m, t.rays[i].origin, t.rays[i].direction, alpha);
      by_hits += covered != (hits[i] != 0);
      if (w[i] < 0.0) continue;  // in neither centroid
      by_weights += covered != (w[i] > 0.0);
    }
    EXPECT_GT(by_hits, 150);
    EXPECT_LT(by_weights, by_hits / 5);
  }
}

// The default plate with calib rig's gate for the simulator's 12 mm of range noise (5 sigma),
// at the plan's recording's true angle.
struct NoisyPlate {
  PlateModel model = PlateModel::fromConfig(PlateConfig{});
  PlateRegion region = PlateRegion::fromConfig(PlateConfig{});
  double alpha = 29.3598 * kDegToRad;
  NoisyPlate() { model.range_gate_m = 5 * 0.012; }
};

// The rays behind the plate's edges graze the floor, whose range climbs by tens of millimetres a
// beam there, and every range has the simulator's 12 mm of noise (the gate 5 sigma): the
// background's first rays then read "between" the plate and the background three beams out,
// and a rule that judged a mixed pixel by that counted floor rays 2 m away as the plate's
// (seed 3 of the plan's recording: alpha -0.024 deg). The ray past a run of hits is the plate's
// last or the background's first, mixed or not, whatever its range: in neither centroid. What
// still differs from the plate's rays at the true angle is the background's mixed pixels that
// fell within the plate's gate (~1 in 60 edges).
TEST(PlateModel, MixedPixelsBeforeAGrazedFloorAreNotCountedAsThePlates) {
  const NoisyPlate p;
  const PlateModel& m = p.model;
  const PlateRegion& region = p.region;
  const double alpha = p.alpha;
  for (const uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(seed);
    const MixedTurn t = mixedFullTurn(m, region, alpha, seed, true, 0.012);
    const auto w = plateHitWeights(m, t.rays, t.beams);
    int differ = 0;
    for (size_t i = 0; i < t.rays.size(); ++i) {
      if (w[i] < 0.0) continue;
      differ += plateCovers(m, t.rays[i].origin, t.rays[i].direction, alpha) != (w[i] > 0.0);
    }
    EXPECT_LT(differ, 20);
  }
}

// One view of a full turn (the rays that leave the lidar on one side of its scan plane, as calib
// rig fits them) with the simulator's mixed pixels over a grazed floor and 12 mm of noise: the
// few rays that stay wrong at the true angle (a background's mixed pixel in the plate's gate, a
// scan that clips a corner) moved the sampled centroid's angle by up to 0.14 deg on the plan's
// recording, because its mismatch is flat wherever no counted ray flips. The angle that
// disagrees with the fewest rays is not moved by them.
TEST(PlateModel, AgreeingFitIsNotMovedByAFewWrongRays) {
  const NoisyPlate p;
  const PlateModel& m = p.model;
  const PlateRegion& region = p.region;
  const double alpha = p.alpha;
  double worst = 0.0, worst_sampled = 0.0;
  for (const uint64_t seed : {1, 2, 3, 4, 5, 6}) {
    SCOPED_TRACE(seed);
    const MixedTurn t = mixedFullTurn(m, region, alpha, seed, true, 0.012);
    const auto all = plateHitWeights(m, t.rays, t.beams);
    // The view whose rays pass the axis on the side of -Y_L (as rig_a_calibration's split).
    std::vector<PlateRay> rays;
    std::vector<double> w;
    for (size_t i = 0; i < t.rays.size(); ++i) {
      const Eigen::Vector3d& o = t.rays[i].origin;
      const Eigen::Vector3d y_l(-o.y(), o.x(), 0.0);
      if (y_l.dot(t.rays[i].direction) >= 0.0) continue;
      rays.push_back(t.rays[i]);
      w.push_back(all[i]);
    }
    const auto agreeing = fitPlateAgreeing(m, rays, w, alpha + 0.1 * kDegToRad);
    const auto sampled = fitPlateSampled(m, rays, w, alpha + 0.1 * kDegToRad);
    ASSERT_TRUE(agreeing.has_value());
    ASSERT_TRUE(sampled.has_value());
    worst = std::max(worst, std::fabs(*agreeing - alpha) / kDegToRad);
    worst_sampled = std::max(worst_sampled, std::fabs(*sampled - alpha) / kDegToRad);
  }
  std::printf("largest error: agreeing %.4f deg, sampled centroid %.4f deg\n", worst,
              worst_sampled);
  EXPECT_LT(worst, 0.01);
  // The case is one the sampled-centroid fit misses (by up to 0.049 deg), or it shows nothing.
  EXPECT_GT(worst_sampled, 0.01);
}

TEST(PlateModel, AgreeingFitWithoutAHitIsNotFound) {
  PlateConfig c;
  const PlateModel m = PlateModel::fromConfig(c);
  const auto rays = fullTurnPlateRays(m, PlateRegion::fromConfig(c), 0.5);
  EXPECT_FALSE(fitPlateAgreeing(m, rays, std::vector<double>(rays.size(), 0.0), 0.5).has_value());
}

// Neighbour records that do not match the rays are a caller's error, not "no neighbours".
TEST(PlateModel, HitWeightsRefuseNeighboursThatDoNotMatchTheRays) {
  const PlateModel m = PlateModel::fromConfig(PlateConfig{});
  const std::vector<PlateRay> rays(3);
  EXPECT_EQ(plateHitWeights(m, rays, {}).size(), 3u);
  EXPECT_THROW(plateHitWeights(m, rays, std::vector<PlateRayBeams>(2)), std::invalid_argument);
}

}  // namespace
}  // namespace sweepmap
