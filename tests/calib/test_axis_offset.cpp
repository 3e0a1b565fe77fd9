// Rig C's plane-constraint calibration (calib/axis_offset.hpp) on the simulated plates: the
// simulator against the truth, ours against the 0.1 mm, the paper's grid and its step,
// the time of both, and the warnings for planes that cannot determine the parameters.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include "calib/axis_offset.hpp"
#include "core/angles.hpp"
#include "profile_test_util.hpp"

namespace sweepmap {
namespace {

using test::rigC;
using test::simulatedPlates;

// The encoder zero is a gauge freedom (planes cannot see it): ours starts from the truth's.
AxisOffsetOptions startFromNominal(const RotatingProfileConfig& rig) {
  AxisOffsetOptions o;
  o.initial = rig.geometry.toGeometry();
  o.initial.encoder_zero_rad = rig.sim.encoder_zero_deg * kDegToRad;
  return o;
}

bool hasWarning(const AxisOffsetResult& r, const std::string& text) {
  for (const auto& w : r.warnings) {
    if (w.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(AxisOffsetSim, PlatePointsLieOnTheTruePlaneWithTheTrueOffsets) {
  // No noise, a fine encoder: what is left is float storage.
  RotatingProfileConfig rig = rigC({"sim.range_noise_sigma_mm=0", "sim.encoder_noise_counts=0",
                                    "turntable.counts_per_revolution=1073741824"});
  const auto poses = platePoses(rig.sim, rig.turntable);
  const auto planes = simulatedPlates(rig, 1, 0);
  ASSERT_EQ(planes.size(), 3u);
  const ProfileGeometry truth = rig.sim.trueGeometry();
  for (size_t k = 0; k < planes.size(); ++k) {
    ASSERT_GT(planes[k].samples.size(), 100000u);
    double worst = 0;
    for (const auto& s : planes[k].samples) {
      const Eigen::Vector3d p = profilePointInRigFrame(truth, s.y_mm, s.z_mm, s.encoder_rad);
      worst = std::max(worst, std::fabs(poses[k].normal.dot(p) - poses[k].distance()));
    }
    EXPECT_LT(worst, 2e-4) << planes[k].source;  // float32 at 400 mm: 3e-5
  }
  // The three poses are not parallel.
  EXPECT_LT(std::fabs(poses[0].normal.dot(poses[1].normal)), std::cos(20 * kDegToRad));
}

TEST(AxisOffsetSim, TestPieceHasTable2sDepths) {
  RotatingProfileConfig rig = rigC({"sim.range_noise_sigma_mm=0", "sim.encoder_noise_counts=0",
                                    "turntable.counts_per_revolution=1073741824"});
  SimProfiler profiler(rig.profiler, rig.turntable, rig.sim, 1);
  const ProfileGeometry truth = rig.sim.trueGeometry();
  std::map<long, size_t> depths;  // depth below the top face [um] -> points
  for (const Profile& p : profiler.sweep(ProfileScene::testPiece(rig.sim, rig.turntable), 0, 0)) {
    const double a = 2 * M_PI * p.encoder_counts / p.counts_per_revolution;
    for (size_t i = 0; i < p.y_mm.size(); ++i) {
      const double z = profilePointInRigFrame(truth, p.y_mm[i], p.z_mm[i], a).z();
      ++depths[std::lround((-rig.sim.test_piece.distance_mm - z) * 1000)];
    }
  }
  const auto near = [&](double depth_mm) {
    size_t n = 0;
    for (const auto& [um, count] : depths) n += std::abs(um - depth_mm * 1000) <= 2 ? count : 0;
    return n;
  };
  EXPECT_GT(near(0.0), 100000u);   // the top face
  EXPECT_GT(near(20.01), 10000u);  // the rectangular groove's bottom
  EXPECT_GT(near(30.03), 10000u);  // the first round groove's
  EXPECT_GT(near(30.02), 10000u);  // the second's
}

// Each of a real part's artefacts alone against the same noise-free sweep without them: the
// simulator does what config/rig_c.yaml says (mixed pixels at steps, dropouts), and the plate,
// which has no step and is never seen at glancing incidence, keeps every point but the spots.
TEST(AxisOffsetSim, ArtefactsEachDoWhatTheySay) {
  const std::vector<std::string> quiet = {
      "sim.range_noise_sigma_mm=0",
      "sim.encoder_noise_counts=0",
      "sim.mixed_pixel_probability=0",
      "sim.dropout_glancing_probability=0",
      "sim.dropout_spot_probability=0",
      "turntable.speed_deg_s=60"};  // a third of the profiles: short enough under ASan
  const auto sweepOf = [&](const std::string& scene, const std::string& set) {
    std::vector<std::string> sets = quiet;
    if (!set.empty()) sets.push_back(set);
    const RotatingProfileConfig rig = rigC(sets);
    SimProfiler profiler(rig.profiler, rig.turntable, rig.sim, 3);
    const ProfileScene s = scene == "plate"
                               ? ProfileScene::plate(platePoses(rig.sim, rig.turntable).front())
                               : ProfileScene::testPiece(rig.sim, rig.turntable);
    // column -> range, per profile
    std::vector<std::map<int, double>> out;
    for (const Profile& p : profiler.sweep(s, 0, 0)) {
      auto& m = out.emplace_back();
      for (size_t i = 0; i < p.column.size(); ++i)
        m[p.column[i]] = std::hypot(p.y_mm[i], p.z_mm[i]);
    }
    return out;
  };
  struct Count {
    size_t clean = 0, kept = 0, lost = 0, moved = 0, between = 0;
  };
  // Every profile's points against the clean sweep's, column by column.
  const auto compare = [](const std::vector<std::map<int, double>>& clean,
                          const std::vector<std::map<int, double>>& with) {
    Count c;
    for (size_t k = 0; k < clean.size(); ++k) {
      for (const auto& [col, r] : clean[k]) {
        ++c.clean;
        const auto it = with[k].find(col);
        if (it == with[k].end()) {
          ++c.lost;
        } else if (std::fabs(it->second - r) < 1e-4) {
          ++c.kept;
        } else {
          ++c.moved;
          for (const int n : {col - 1, col + 1}) {  // between its range and a neighbour's
            const auto o = clean[k].find(n);
            if (o != clean[k].end() && it->second > std::min(r, o->second) - 1e-4 &&
                it->second < std::max(r, o->second) + 1e-4) {
              ++c.between;
              break;
            }
          }
        }
      }
      for (const auto& [col, r] : with[k]) EXPECT_TRUE(clean[k].count(col)) << "a new point";
    }
    return c;
  };
  for (const std::string scene : {"plate", "test_piece"}) {
    SCOPED_TRACE(scene);
    const auto clean = sweepOf(scene, "");
    const Count spot = compare(clean, sweepOf(scene, "sim.dropout_spot_probability=0.2"));
    EXPECT_EQ(spot.moved, 0u);
    EXPECT_NEAR(double(spot.lost) / double(spot.clean), 0.2, 0.01);
    const Count glancing = compare(clean, sweepOf(scene, "sim.dropout_glancing_probability=1"));
    EXPECT_EQ(glancing.moved, 0u);
    const Count mixed = compare(clean, sweepOf(scene, "sim.mixed_pixel_probability=1"));
    EXPECT_EQ(mixed.lost, 0u);
    EXPECT_EQ(mixed.between, mixed.moved);
    if (scene == "plate") {
      EXPECT_EQ(glancing.lost, 0u);  // incidence below 50 deg
      EXPECT_EQ(mixed.moved, 0u);    // no step
    } else {
      // The grooves' walls, seen within a few degrees of grazing, and their rims and corners.
      EXPECT_GT(glancing.lost, clean.size());
      EXPECT_GT(mixed.moved, clean.size());
      EXPECT_GT(mixed.kept, 10 * mixed.moved);  // a steep wall is no step
    }
    std::printf("%s: %zu points; spots lose %zu, glancing incidence %zu, mixed pixels move %zu\n",
                scene.c_str(), spot.clean, spot.lost, glancing.lost, mixed.moved);
  }
}

TEST(AxisOffsetPaper, MomentsGiveEq13AndEq14) {
  const RotatingProfileConfig rig = rigC();
  const auto planes = simulatedPlates(rig, 1, 3000);
  const PlaneRmseObjective objective(planes);
  double s = 0;
  for (const auto& plane : planes) {
    std::vector<Eigen::Vector3d> pts;
    for (const auto& q : plane.samples)
      pts.push_back(zhaoEq7(121.0, 411.0, q.encoder_rad, q.y_mm, q.z_mm));
    s += planeRmseEq14(pts, fitPlaneEq13(pts));
  }
  // The direct normal equations (uncentred, coordinates ~400 mm) lose a few digits.
  EXPECT_NEAR(objective.meanRmse(121.0, 411.0), s / planes.size(), 1e-7);
}

TEST(AxisOffsetOurs, RecoversMAndNWithinATenthOfAMillimetre) {
  std::printf("seed  |dM| mm  |dN| mm  sigma_M  sigma_N  tilt err deg\n");
  for (const uint64_t seed : {1, 2, 3, 4, 5, 6}) {  // the default and five others
    const RotatingProfileConfig rig = rigC();
    const AxisOffsetResult r = solveAxisOffset(simulatedPlates(rig, seed), startFromNominal(rig));
    const double dm = std::fabs(r.geometry.m_mm - rig.sim.offset_m_mm);
    const double dn = std::fabs(r.geometry.n_mm - rig.sim.offset_n_mm);
    std::printf("%4d  %7.4f  %7.4f  %7.4f  %7.4f  %+8.5f\n", static_cast<int>(seed), dm, dn,
                r.sigma_m_mm, r.sigma_n_mm,
                r.geometry.laser_tilt_rad / kDegToRad - rig.sim.laser_tilt_deg);
    EXPECT_LT(dm, 0.1) << "seed " << seed;
    EXPECT_LT(dn, 0.1) << "seed " << seed;
    EXPECT_TRUE(r.observable);
    EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
    EXPECT_TRUE(std::isfinite(r.sigma_m_mm) && r.sigma_m_mm > 0 && r.sigma_m_mm < 0.1);
    EXPECT_LT(r.rms_after_mm, 0.03);
  }
}

TEST(AxisOffsetPaper, GridCannotBeatItsStep) {
  // Without the tilt the paper's model is exact; its answer is still a node of the grid.
  const RotatingProfileConfig rig = rigC({"sim.laser_tilt_deg=0"});
  const auto planes = simulatedPlates(rig, 1, 5000);
  GridSearchOptions g;  // the paper's interval, 1 mm
  const GridSearchResult r = gridSearchAxisOffset(planes, g);
  EXPECT_EQ(r.m_values.size(), 21u);
  EXPECT_EQ(r.n_values.size(), 31u);
  EXPECT_EQ(r.m_mm, std::round(r.m_mm));
  EXPECT_EQ(r.n_mm, std::round(r.n_mm));
  EXPECT_LE(std::fabs(r.m_mm - 123.0), 1.0);
  EXPECT_LE(std::fabs(r.n_mm - 409.0), 1.0);
  // Truth off the grid by 0.4 mm: the grid's error is at least that.
  const RotatingProfileConfig off =
      rigC({"sim.laser_tilt_deg=0", "sim.offset_m_mm=122.6", "sim.offset_n_mm=409.4"});
  const GridSearchResult o = gridSearchAxisOffset(simulatedPlates(off, 1, 5000), g);
  EXPECT_GE(std::fabs(o.m_mm - 122.6), 0.4 - 1e-9);
  EXPECT_GE(std::fabs(o.n_mm - 409.4), 0.4 - 1e-9);
  std::printf("grid 1 mm: truth (122.6, 409.4) -> (%.1f, %.1f), min S %.4f mm\n", o.m_mm, o.n_mm,
              o.s_min_mm);
}

TEST(AxisOffsetBenchmark, OursAgainstTheGridAtATenthOfAMillimetre) {
  const RotatingProfileConfig rig = rigC();
  const auto planes = simulatedPlates(rig, 1, 5000);
  const AxisOffsetResult ours = solveAxisOffset(planes, startFromNominal(rig));
  GridSearchOptions fine;
  fine.step_mm = 0.1;  // 10x the paper's resolution over its interval
  const GridSearchResult grid = gridSearchAxisOffset(planes, fine);
  GridSearchOptions paper;
  const GridSearchResult coarse = gridSearchAxisOffset(planes, paper);
  std::printf(
      "points %zu: ours %.3f s (M %.3f N %.3f); grid 1 mm %.3f s (%zu nodes: M %.1f N %.1f); "
      "grid 0.1 mm %.3f s (%zu nodes: M %.1f N %.1f); grid 0.1 mm / ours = %.0fx\n",
      ours.residuals, ours.seconds, ours.geometry.m_mm, ours.geometry.n_mm, coarse.seconds,
      coarse.s_mm.size(), coarse.m_mm, coarse.n_mm, grid.seconds, grid.s_mm.size(), grid.m_mm,
      grid.n_mm, grid.seconds / ours.seconds);
  EXPECT_EQ(grid.s_mm.size(), 201u * 301u);
}

TEST(AxisOffsetOurs, ParallelPlatesAreReportedNotDetermined) {
  const RotatingProfileConfig rig = rigC({"sim.plate_tilt_spread_deg=0"});
  const AxisOffsetResult r = solveAxisOffset(simulatedPlates(rig, 1, 5000), startFromNominal(rig));
  EXPECT_FALSE(r.observable);
  EXPECT_TRUE(hasWarning(r, "the planes are parallel")) << r.warnings.size();
  EXPECT_LT(r.largest_plane_angle_deg, 1.0);
}

TEST(AxisOffsetOurs, LevelPlatesLeaveMAndNUndetermined) {
  const RotatingProfileConfig rig = rigC({"sim.plate_tilt_deg=0"});
  AxisOffsetOptions o = startFromNominal(rig);
  o.estimate_tilt = false;
  o.max_iterations = 20;
  const AxisOffsetResult r = solveAxisOffset(simulatedPlates(rig, 1, 3000), o);
  EXPECT_FALSE(r.observable);
  EXPECT_TRUE(hasWarning(r, "M is poorly determined") || hasWarning(r, "not observable") ||
              hasWarning(r, "parallel"));
}

TEST(AxisOffsetOurs, EncoderZeroIsNotObservableFromPlanes) {
  const RotatingProfileConfig rig = rigC();
  AxisOffsetOptions o = startFromNominal(rig);
  o.estimate_encoder_zero = true;
  const AxisOffsetResult r = solveAxisOffset(simulatedPlates(rig, 1, 5000), o);
  EXPECT_TRUE(hasWarning(r, "encoder_zero is not observable"));
  EXPECT_FALSE(r.zero_estimated);
  EXPECT_DOUBLE_EQ(r.geometry.encoder_zero_rad, o.initial.encoder_zero_rad);
  EXPECT_TRUE(r.observable);  // M and N still are
  EXPECT_LT(std::fabs(r.geometry.m_mm - 123.0), 0.1);
}

// The base's reference face (a fence whose normal's azimuth is known) defines X_r: with a
// sweep over it the zero is determined, from the rig file's nominal 0 to the truth 0.5 deg.
struct ReferenceRun {
  std::vector<size_t> found;
  AxisOffsetResult result;
};
ReferenceRun solveWithReference(const RotatingProfileConfig& rig, double azimuth_sigma_deg) {
  const auto planes = simulatedPlates(rig, 2, 5000);
  AxisOffsetOptions o;
  o.initial = rig.geometry.toGeometry();  // encoder zero 0
  o.estimate_encoder_zero = true;
  o.reference_azimuth_rad = rig.turntable.reference.normal_azimuth_deg * kDegToRad;
  o.reference_azimuth_sigma_rad = azimuth_sigma_deg * kDegToRad;
  o.reference_planes =
      findReferencePlanes(planes, o.initial, o.reference_azimuth_rad,
                          rig.turntable.reference.normal_tilt_deg * kDegToRad, 5 * kDegToRad);
  return {o.reference_planes, solveAxisOffset(planes, o)};
}

TEST(AxisOffsetOurs, EncoderZeroFromTheBasesReferenceFace) {
  // The face exactly where the rig file says: what is left is the fit's own error.
  const RotatingProfileConfig rig =
      rigC({"sim.reference_sweep=true", "sim.reference_azimuth_deg=0"});
  const ReferenceRun run = solveWithReference(rig, 0.0);
  ASSERT_EQ(run.found, std::vector<size_t>{3});  // after the 3 plate poses, none of them
  const AxisOffsetResult& r = run.result;
  ASSERT_TRUE(r.zero_estimated) << (r.warnings.empty() ? "" : r.warnings.front());
  EXPECT_FALSE(hasWarning(r, "not observable"));
  const double zero_deg = r.geometry.encoder_zero_rad / kDegToRad;
  EXPECT_GT(r.sigma_zero_deg, 0.0);
  EXPECT_LT(r.sigma_zero_deg, 0.01);
  EXPECT_LE(std::fabs(zero_deg - rig.sim.encoder_zero_deg), 3 * r.sigma_zero_deg) << zero_deg;
  EXPECT_NEAR(r.sigma_zero_fit_deg, r.sigma_zero_deg, 1e-12);
  EXPECT_LT(std::fabs(r.geometry.m_mm - rig.sim.offset_m_mm), 0.1);
  EXPECT_LT(std::fabs(r.geometry.n_mm - rig.sim.offset_n_mm), 0.1);
}

TEST(AxisOffsetOurs, EncoderZeroIsMeasuredAgainstTheReferenceFace) {
  // A fence 0.3 deg off square turns X_r with it: the zero follows one for one, and the
  // construction's sigma is added to the fit's.
  const RotatingProfileConfig rig =
      rigC({"sim.reference_sweep=true", "sim.reference_azimuth_deg=0.3"});
  const ReferenceRun run = solveWithReference(rig, 0.02);
  const AxisOffsetResult& r = run.result;
  ASSERT_TRUE(r.zero_estimated);
  EXPECT_NEAR(r.geometry.encoder_zero_rad / kDegToRad, 0.5 + 0.3, 3 * r.sigma_zero_fit_deg);
  EXPECT_NEAR(r.sigma_zero_deg, std::hypot(r.sigma_zero_fit_deg, 0.02), 1e-12);
}

TEST(AxisOffsetOurs, WithoutTheReferenceFaceTheZeroIsHeldNominal) {
  // The same recording, the face's sweep not declared as one: just a fourth plane.
  const RotatingProfileConfig rig = rigC({"sim.reference_sweep=true"});
  AxisOffsetOptions o;
  o.initial = rig.geometry.toGeometry();
  o.estimate_encoder_zero = true;
  const AxisOffsetResult r = solveAxisOffset(simulatedPlates(rig, 2, 5000), o);
  EXPECT_FALSE(r.zero_estimated);
  EXPECT_TRUE(hasWarning(r, "encoder_zero is not observable"));
  EXPECT_TRUE(hasWarning(r, "reference face"));
  EXPECT_EQ(r.geometry.encoder_zero_rad, 0.0);
  EXPECT_LT(std::fabs(r.geometry.m_mm - rig.sim.offset_m_mm), 0.1);
}

// calib rig's correlations: the covariance's diagonal is the sigmas squared, it is symmetric,
// and a parameter not estimated has NaN in its row (the encoder zero here).
TEST(AxisOffsetOurs, CovarianceMatchesTheSigmas) {
  const RotatingProfileConfig rig = rigC();
  AxisOffsetOptions o = startFromNominal(rig);
  o.estimate_encoder_zero = true;
  const AxisOffsetResult r = solveAxisOffset(simulatedPlates(rig, 1, 5000), o);
  ASSERT_TRUE(r.tilt_estimated);
  EXPECT_NEAR(std::sqrt(r.covariance(0, 0)), r.sigma_m_mm, 1e-12);
  EXPECT_NEAR(std::sqrt(r.covariance(1, 1)), r.sigma_n_mm, 1e-12);
  EXPECT_NEAR(std::sqrt(r.covariance(2, 2)), r.sigma_tilt_deg, 1e-12);
  EXPECT_NEAR(r.covariance(0, 2), r.covariance(2, 0), 1e-12 * std::fabs(r.covariance(0, 2)));
  EXPECT_GT(std::fabs(r.covariance(0, 2)), 0.0);  // M and the tilt trade off
  EXPECT_TRUE(std::isnan(r.covariance(3, 3)));
}

TEST(AxisOffsetOurs, RejectsTooFewPoints) {
  EXPECT_THROW(solveAxisOffset({}, AxisOffsetOptions{}), std::invalid_argument);
  PlanePoints few{"log sweep 0", {{0, -300, 0}, {1, -300, 0}}};
  try {
    solveAxisOffset({few}, AxisOffsetOptions{});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("log sweep 0"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sweepmap
