// `sweepmap eval` of a rotating_lidar rig: the pieces (E_map distance, deviation statistics,
// wall-point selection) on hand cases, and the command end to end on a small simulated paper
// experiment, on simulated logs with truth, and on a log without any rig-A sweep.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/angles.hpp"
#include "tests/e2e/test_support.hpp"
#include "tools/eval/eval_rotating.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");

// --- pieces ---------------------------------------------------------------------------

TEST(MapErrorDistance, Eq21) {
  EXPECT_DOUBLE_EQ(mapErrorDistance(0.0, 0.05, 10.0), 10.0);
  EXPECT_NEAR(mapErrorDistance(0.5 * kDegToRad, 0.05, 10.0), 0.05 / std::tan(0.5 * kDegToRad),
              1e-12);
  EXPECT_NEAR(mapErrorDistance(-0.5 * kDegToRad, 0.05, 10.0), 0.05 / std::tan(0.5 * kDegToRad),
              1e-12);
  // The paper's mode 1: 50 mm at 2.2996 m <=> |phi_error| = atan(0.05 / 2.2996).
  EXPECT_NEAR(mapErrorDistance(std::atan(0.05 / 2.2996), 0.05, 10.0), 2.2996, 1e-9);
  // Exactly 50 mm at 10 m is still within.
  EXPECT_DOUBLE_EQ(mapErrorDistance(std::atan(0.005), 0.05, 10.0), 10.0);
}

TEST(DeviationStats, BinsRmsShareAndMerge) {
  DeviationStats a(2.0, 100.0);
  ASSERT_EQ(a.bins.size(), 100u);
  for (double d : {-50.0, -1.0, 0.0, 3.0, 39.9, 40.0, 120.0}) a.add(d, 40.0);
  EXPECT_EQ(a.count, 7);
  EXPECT_EQ(a.within, 5);  // -1, 0, 3, 39.9, 40
  EXPECT_EQ(a.outside_range, 1);
  EXPECT_EQ(a.bins[50 - 1], 1);  // -1 mm: [-2, 0)
  EXPECT_EQ(a.bins[50], 1);      // 0 mm: [0, 2)
  EXPECT_EQ(a.bins[25], 1);      // -50 mm: [-50, -48)
  const double ss = 2500 + 1 + 0 + 9 + 39.9 * 39.9 + 1600 + 14400;
  EXPECT_NEAR(a.rmsMm(), std::sqrt(ss / 7), 1e-9);
  EXPECT_NEAR(a.shareWithin(), 5.0 / 7.0, 1e-12);
  EXPECT_DOUBLE_EQ(a.binCenterMm(50), 1.0);

  DeviationStats b(2.0, 100.0);
  b.add(10.0, 40.0);
  a.merge(b);
  EXPECT_EQ(a.count, 8);
  EXPECT_EQ(a.bins[55], 1);
  DeviationStats empty;
  empty.merge(b);
  EXPECT_EQ(empty.count, 1);
  EXPECT_EQ(DeviationStats(2.0, 100.0).shareWithin(), 0.0);
}

// A 6 x 4 m box room with noisy walls, floor and ceiling, the sensor at the origin.
std::vector<Eigen::Vector3f> boxRoom(double sigma_m, std::vector<PlaneForDeviation>* walls) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, sigma_m);
  std::vector<Eigen::Vector3f> cloud;
  const double x0 = -3, x1 = 3, y0 = -2, y1 = 2, z0 = -1, z1 = 2;
  for (double a = 0; a <= 1.0; a += 0.005) {
    for (double z = z0; z <= z1; z += 0.02) {
      cloud.emplace_back(x0 + noise(rng), y0 + a * (y1 - y0), z);
      cloud.emplace_back(x1 + noise(rng), y0 + a * (y1 - y0), z);
      cloud.emplace_back(x0 + a * (x1 - x0), y0 + noise(rng), z);
      cloud.emplace_back(x0 + a * (x1 - x0), y1 + noise(rng), z);
    }
    for (double b = 0; b <= 1.0; b += 0.01) {  // floor and ceiling
      cloud.emplace_back(x0 + a * (x1 - x0), y0 + b * (y1 - y0), z0 + noise(rng));
      cloud.emplace_back(x0 + a * (x1 - x0), y0 + b * (y1 - y0), z1 + noise(rng));
    }
  }
  // Normals toward the origin: n.p + offset = 0.
  *walls = {{Eigen::Vector3d::UnitX(), 3.0},
            {-Eigen::Vector3d::UnitX(), 3.0},
            {Eigen::Vector3d::UnitY(), 2.0},
            {-Eigen::Vector3d::UnitY(), 2.0}};
  return cloud;
}

TEST(WallDeviations, NoiseOnlyAwayFromCornersFloorAndCeiling) {
  std::vector<PlaneForDeviation> walls;
  const auto cloud = boxRoom(0.012, &walls);
  const auto dev = wallDeviationsMm(cloud, walls, 0.10, 0.15);
  ASSERT_EQ(dev.size(), 4u);
  DeviationStats all(2.0, 100.0);
  for (const auto& w : dev) {
    EXPECT_GT(w.size(), 1000u);
    for (double d : w) all.add(d, 40.0);
  }
  // Floor, ceiling and the neighbouring walls near the corners would add deviations up to
  // 100 mm; with them trimmed only the 12 mm noise is left.
  EXPECT_NEAR(all.rmsMm(), 12.0, 0.6);
  EXPECT_GT(all.shareWithin(), 0.998);
  EXPECT_EQ(all.outside_range, 0);
}

TEST(WallDeviations, BentWallSpreadsAndLeavesTheBand) {
  std::vector<PlaneForDeviation> walls;
  auto cloud = boxRoom(0.0, &walls);
  // Bend the x = 3 wall: x grows with y up to 80 mm at the ends (shape error).
  for (auto& p : cloud) {
    if (std::abs(p.x() - 3.0) < 1e-6) p.x() += static_cast<float>(0.08 * p.y() * p.y() / 4.0);
  }
  const auto dev = wallDeviationsMm(cloud, {walls[1]}, 0.10, 0.15);
  DeviationStats bent(2.0, 100.0);
  for (double d : dev[0]) bent.add(d, 40.0);
  EXPECT_GT(bent.rmsMm(), 20.0);
  EXPECT_LT(bent.shareWithin(), 0.9);
}

// --- the command --------------------------------------------------------------------------

bool isPng(const fs::path& p) {
  const std::string head = readFile(p).substr(0, 8);
  return head == std::string("\x89PNG\r\n\x1a\n", 8);
}

void expectFiguresExistAndReferenced(const fs::path& dir, const nlohmann::json& report) {
  const std::string md = readFile(dir / "report.md");
  ASSERT_TRUE(report.contains("figures"));
  for (const auto& f : report["figures"]) {
    const std::string name = f.get<std::string>();
    EXPECT_TRUE(isPng(dir / name)) << name;
    EXPECT_NE(md.find("](" + name + ")"), std::string::npos) << name << " not in report.md";
  }
  // Every PNG in the directory is in report.md.
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() != ".png") continue;
    EXPECT_NE(md.find("](" + e.path().filename().string() + ")"), std::string::npos) << e.path();
  }
}

// The paper's experiment, small: 2 sweeps per mode, 10 mode-7 sweeps for alpha.
TEST(EvalRotating, SmallPaperExperiment) {
  const fs::path dir = scratchDir("eval_paper_small");
  const int rc = sweepmap(
      {"eval", "--experiment", "paper", "--rig", kRig, "--scene", kScene, "--sweeps-per-mode", "2",
       "--calib-sweeps", "10", "--seed", "1", "--out", dir.string()},
      fs::path(dir.string() + ".stderr.txt"));
  ASSERT_EQ(rc, 0) << readFile(fs::path(dir.string() + ".stderr.txt"));
  const auto report = readJson(dir / "report.json");
  EXPECT_EQ(report["sweeps"].get<int>(), 14);

  for (int mode = 1; mode <= 7; ++mode) {
    const std::string m = std::to_string(mode);
    SCOPED_TRACE("mode " + m);
    ASSERT_TRUE(report["d50_m"].contains(m));
    ASSERT_TRUE(report["d50_m_centroid"].contains(m));
    const double d50 = report["d50_m"][m].get<double>();
    EXPECT_GT(d50, 0.0);
    EXPECT_LE(d50, 10.0);
    const auto& mj = report["modes"][m];
    ASSERT_EQ(mj["sweeps"].size(), 2u);
    for (const auto& s : mj["sweeps"]) {
      EXPECT_TRUE(s["corrected"].get<bool>()) << s.dump();
      for (const char* k : {"ray_plane", "centroid", "uncorrected"}) {
        EXPECT_TRUE(s["phi_error_deg"].contains(k)) << s.dump();
      }
      EXPECT_EQ(s["walls"].get<int>(), 4) << s.dump();
    }
    for (const char* k : {"ray_plane", "centroid", "uncorrected"}) {
      const auto& st = mj["phi_error_deg"][k];
      EXPECT_LE(st["min"].get<double>(), st["mean"].get<double>());
      EXPECT_LE(st["mean"].get<double>(), st["max"].get<double>());
    }
    // Appendix B: wall points lie within the lidar's +-40 mm (12 mm noise).
    const auto& walls = mj["walls"];
    EXPECT_GT(walls["points"].get<int64_t>(), 1000);
    EXPECT_LT(walls["rms_mm"].get<double>(), 16.0);
    EXPECT_GT(walls["share_within_40mm"].get<double>(), 0.99);
  }
  // The paper's floor that 2 sweeps support: mode 7 stays within 50 mm over the full 10 m.
  EXPECT_DOUBLE_EQ(report["d50_m"]["7"].get<double>(), 10.0);
  EXPECT_LT(report["modes"]["7"]["phi_error_deg"]["ray_plane"]["max_abs"].get<double>(), 0.2);

  // Alpha: calibrated from 10 mode-7 sweeps against the simulator's 29.3598 deg.
  ASSERT_TRUE(report.contains("alpha_deg"));
  ASSERT_TRUE(report.contains("alpha_true_deg"));
  EXPECT_NEAR(report["alpha_true_deg"].get<double>(), 29.3598, 1e-6);
  EXPECT_NEAR(report["alpha_deg"].get<double>(), 29.3598, 0.1);
  const auto& lm = report["alpha_calibration"]["ray_plane"];
  EXPECT_EQ(lm["sweeps_used"].get<int>(), 10);
  ASSERT_GE(lm["history"].size(), 1u);
  EXPECT_NEAR(lm["history"][0]["alpha_deg"].get<double>(), 30.0, 1e-9);
  EXPECT_TRUE(report["alpha_calibration"]["applied_to_evaluation"].get<bool>());
  const auto calib = readFile(dir / "plate_calibration.yaml");
  EXPECT_NE(calib.find("alpha_deg"), std::string::npos);

  // Shape: the naive sequence's sweeps are published uncorrected and spread the walls.
  const auto& shape = report["shape"];
  for (const auto& s : shape["naive"]["sweeps"]) {
    EXPECT_FALSE(s["corrected"].get<bool>());
    EXPECT_NE(s["reason"].get<std::string>().find("ramp overlapped"), std::string::npos);
  }
  EXPECT_GT(shape["naive_rms_mm"].get<double>(), shape["improved_rms_mm"].get<double>());
  EXPECT_LT(shape["naive_share_within_40mm"].get<double>(),
            shape["improved_share_within_40mm"].get<double>());

  // Simulator settings and seeds are recorded.
  const auto& exp = report["inputs"]["experiment"];
  EXPECT_DOUBLE_EQ(exp["simulator"]["sim.alpha_true_deg"].get<double>(), 29.3598);
  EXPECT_EQ(exp["seeds"]["mode7.lcmlog"].get<int>(), 8);

  for (const char* png :
       {"fig8_top_view_mode1.png", "fig9_phi_error.png", "fig10_phi_error_stats.png",
        "fig11_map_error_mode1.png", "figA2_wall_deviations_mode7.png",
        "fig_alpha_calibration_cost.png", "fig_alpha_calibration_alpha.png",
        "fig1_naive_top_view.png", "fig1_shape_deviations.png", "cloud_3d.png", "map_3d.png"}) {
    EXPECT_TRUE(isPng(dir / png)) << png;
  }
  expectFiguresExistAndReferenced(dir, report);
}

std::vector<std::string> simArgs(int mode, int sweeps, int seed) {
  std::vector<std::string> a = {"--rig",    kRig,
                                "--scene",  kScene,
                                "--mode",   std::to_string(mode),
                                "--sweeps", std::to_string(sweeps),
                                "--seed",   std::to_string(seed)};
  const auto paper = paperModelArgs();  // the paper's error model
  a.insert(a.end(), paper.begin(), paper.end());
  return a;
}

TEST(EvalRotating, LogsWithTruth) {
  const std::string mode7 = cachedSimLog("eval_mode7x1", simArgs(7, 1, 21));
  const std::string mode1 = cachedSimLog("eval_mode1x2", simArgs(1, 2, 22));
  const fs::path dir = scratchDir("eval_logs_truth");
  const int rc =
      sweepmap({"eval", "--logs", mode1, mode7, "--rig", kRig, "--out", dir.string(), "--no-plots"},
               fs::path(dir.string() + ".stderr.txt"));
  ASSERT_EQ(rc, 0) << readFile(fs::path(dir.string() + ".stderr.txt"));
  const auto report = readJson(dir / "report.json");
  EXPECT_EQ(report["sweeps"].get<int>(), 3);
  EXPECT_EQ(report["modes"]["1"]["sweeps"].size(), 2u);
  EXPECT_EQ(report["modes"]["7"]["sweeps"].size(), 1u);
  EXPECT_TRUE(report["d50_m"].contains("1"));
  EXPECT_TRUE(report["d50_m"].contains("7"));
  EXPECT_NEAR(report["alpha_true_deg"].get<double>(), 29.3598, 1e-6);
  // Alpha from the one mode-7 sweep; the logs themselves are evaluated with the rig's 30 deg,
  // so the corrected phi_error carries the installation error (about +0.64 deg).
  ASSERT_TRUE(report.contains("alpha_deg"));
  EXPECT_NEAR(report["alpha_deg"].get<double>(), 29.3598, 0.2);
  EXPECT_FALSE(report["alpha_calibration"]["applied_to_evaluation"].get<bool>());
  const double e7 = report["modes"]["7"]["sweeps"][0]["phi_error_deg"]["ray_plane"].get<double>();
  EXPECT_NEAR(e7, 30.0 - 29.3598, 0.2);
  EXPECT_TRUE(report["figures"].empty());
}

// lcm's example log has no rig-A channel: no sweep, a clear message, exit 1, and a
// report that says so (no truth, no phi_error, no alpha).
TEST(EvalRotating, LogWithoutSweepsReportsAndFails) {
  const std::string log = std::string(SWEEPMAP_SHARED_DIR) + "/data/real/lcm_example.lcmlog";
  if (!fs::exists(log))
    GTEST_SKIP() << log << " not present (../shared is not beside this checkout)";
  const fs::path dir = scratchDir("eval_no_sweeps");
  const int rc = sweepmap({"eval", "--logs", log, "--rig", kRig, "--out", dir.string()},
                          fs::path(dir.string() + ".stderr.txt"));
  EXPECT_EQ(rc, 1);
  EXPECT_NE(readFile(fs::path(dir.string() + ".stderr.txt")).find("no sweeps"), std::string::npos)
      << readFile(fs::path(dir.string() + ".stderr.txt"));
  const auto report = readJson(dir / "report.json");
  EXPECT_EQ(report["sweeps"].get<int>(), 0);
  EXPECT_NE(report["error"].get<std::string>().find("no sweeps"), std::string::npos);
  EXPECT_FALSE(report.contains("alpha_true_deg"));
  EXPECT_FALSE(report.contains("alpha_deg"));
  EXPECT_FALSE(report.contains("d50_m"));
  EXPECT_TRUE(report["modes"].empty());
  EXPECT_TRUE(fs::exists(dir / "report.md"));
}

TEST(EvalRotating, UsageErrors) {
  const fs::path dir = scratchDir("eval_usage");
  EXPECT_EQ(sweepmap({"eval", "--rig", kRig, "--out", dir.string()}), 2);
  EXPECT_NE(sweepmap({"eval", "--experiment", "other", "--rig", kRig, "--out", dir.string()}), 0);
  EXPECT_NE(sweepmap({"eval", "--logs", (dir / "missing.lcmlog").string(), "--out", dir.string()}),
            0);
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
