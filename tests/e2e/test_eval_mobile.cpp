// `sweepmap eval` of a mobile_lidar rig: the paper's experiment for rig B (calibration circle + lab
// loop) against the simulator's truth, and bad input (corrupt and truncated logs).
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

#include "tests/e2e/test_support.hpp"

namespace sweepmap {
namespace test {
namespace {

// One run of the paper experiment (~3 min) per build, shared by every test (CTest runs each
// in its own process).
class EvalMobilePaper : public ::testing::Test {
 protected:
  void SetUp() override {
    // By name: the rig and its default scene are found in the install tree, not the
    // working directory (the tests run in the build tree, which has no config/ folder).
    const CachedRun run =
        cachedRun("eval_mobile_paper", {"eval", "--experiment", "paper", "--rig", "rig_b"});
    dir_ = run.out;
    ASSERT_EQ(run.status, 0) << readFile(run.output);
    report_ = readJson(dir_ / "report.json");
  }
  fs::path dir_;
  nlohmann::json report_;
};

TEST_F(EvalMobilePaper, OurMountingCalibrationIsWithinOneMilliradianOfTruth) {
  const auto& e = report_["mounting_error_mrad"];
  ASSERT_TRUE(e.is_object()) << report_.dump(2);
  for (const char* k : {"gamma", "beta", "alpha"}) {
    EXPECT_LE(std::abs(e[k].get<double>()), 1.0) << k;
  }
  // The paper's method runs on the same data and is reported beside ours.
  const auto& paper = report_["calibration"]["paper"];
  EXPECT_EQ(paper["method"], "paper_points");
  EXPECT_TRUE(report_["calibration"]["ours"]["residual_after_m"].get<double>() <
              report_["calibration"]["ours"]["residual_before_m"].get<double>());
  // The written calibration is a mounting calibration file.
  EXPECT_NE(readFile(dir_ / "mounting_calibration.yaml").find("gamma_rad"), std::string::npos);
}

TEST_F(EvalMobilePaper, CalibrationRemovesTheCirclesDoubleWalls) {
  const auto& g = report_["calibration"]["circle_double_wall_mm"];
  ASSERT_TRUE(g["before"]["max_mm"].is_number()) << g.dump();
  ASSERT_TRUE(g["after"]["max_mm"].is_number()) << g.dump();
  EXPECT_GT(g["before"]["max_mm"].get<double>(), 30.0);
  EXPECT_LT(g["after"]["max_mm"].get<double>(), 15.0);
}

TEST_F(EvalMobilePaper, EkfBeatsWheelOdometryByAtLeastTwoOnTheLoopWithSlip) {
  const double odo = report_["trajectory_rmse_m"]["odometry"].get<double>();
  const double ekf = report_["trajectory_rmse_m"]["ekf"].get<double>();
  EXPECT_GE(odo, 2.0 * ekf) << "odometry " << odo << " m, EKF " << ekf << " m";
  EXPECT_GT(report_["trajectory"]["wheel_readings_gated"].get<int>(), 0)
      << "slip is caught by the gate";
}

TEST_F(EvalMobilePaper, RoomDimensionsWithinTenMillimetres) {
  for (const char* k : {"L1", "L2", "L3"}) {
    ASSERT_TRUE(report_["room_dims_error_mm"][k].is_number()) << report_["planes"].dump(2);
    EXPECT_LE(std::abs(report_["room_dims_error_mm"][k].get<double>()), 10.0) << k;
  }
  EXPECT_NEAR(report_["room_dims_truth_m"]["L1"].get<double>(), 10.0, 1e-9);
}

TEST_F(EvalMobilePaper, NoGhostOverThirtyMillimetresWhereTheLoopCloses) {
  ASSERT_TRUE(report_["ghost_mm"].is_number()) << report_["loop_closure"].dump(2);
  EXPECT_LE(report_["ghost_mm"].get<double>(), 30.0);
  // The walls measured are the room's that both passes see: where the loop closes (0.5 m
  // from a long wall), that one and the far one, 4.5 m away, not slices of floor or furniture.
  const auto& planes = report_["loop_closure"]["planes"];
  ASSERT_EQ(planes.size(), 2u) << planes.dump(2);
  std::vector<double> ranges;
  for (const auto& p : planes) {
    EXPECT_GE(p["early_points"].get<int>(), 100);
    EXPECT_GE(p["late_points"].get<int>(), 100);
    ranges.push_back(p["range_m"].get<double>());
  }
  std::sort(ranges.begin(), ranges.end());
  EXPECT_NEAR(ranges[0], 0.5, 0.1);
  EXPECT_NEAR(ranges[1], 4.5, 0.1);
}

TEST_F(EvalMobilePaper, CeilingNormalDensityAndFigures) {
  const auto& n = report_["ceiling_normal"];
  ASSERT_TRUE(n.is_array());
  EXPECT_GT(n[2].get<double>(), 0.999);
  EXPECT_GT(report_["density_D_m"].get<double>(), 0.0);
  EXPECT_LT(report_["density_D_m"].get<double>(), 0.1);
  for (const char* f :
       {"trajectory.png", "trajectory_error.png", "top_view.png", "side_view_xz.png",
        "side_view_yz.png", "deviation_ceiling.png", "deviation_walls.png", "loop_closure.png",
        "circle_ghost_before.png", "circle_ghost_after.png"}) {
    EXPECT_TRUE(fs::exists(dir_ / f)) << f;
  }
  EXPECT_TRUE(fs::exists(dir_ / "report.md"));
  EXPECT_TRUE(fs::exists(dir_ / "logs" / "circle.lcmlog"));
}

TEST(EvalMobile, TruncatedLogIsReportedAndWhatCameBeforeIsEvaluated) {
  const auto dir = scratchDir("eval_mobile_truncated");
  const std::string log = (dir / "drive.lcmlog").string();
  ASSERT_EQ(
      sweepmap({"sim", "--rig", sourcePath("config/rig_b.yaml"), "--scene",
                sourcePath("config/scene_lab.yaml"), "--set", "sim.duration_s=12", "--out", log},
               dir / "sim.txt"),
      0);
  const std::string bytes = readFile(log);
  {
    std::ofstream f(log, std::ios::binary | std::ios::trunc);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size() * 2 / 3 + 7));
  }
  const int status = sweepmap({"eval", "--log", log, "--rig", sourcePath("config/rig_b.yaml"),
                               "--no-plots", "--out", (dir / "eval").string()},
                              dir / "eval.txt");
  EXPECT_EQ(status, 1);
  const std::string out = readFile(dir / "eval.txt");
  EXPECT_NE(out.find("drive.lcmlog"), std::string::npos) << out;
  EXPECT_NE(out.find("byte "), std::string::npos) << out;  // the byte offset of the damage
  const auto r = readJson(dir / "eval" / "report.json");
  EXPECT_GT(r["scans"].get<int>(), 20);
  EXPECT_TRUE(r.contains("log_error"));
}

TEST(EvalMobile, MissingLogAndBadConfigAreClearErrors) {
  const auto dir = scratchDir("eval_mobile_bad");
  EXPECT_NE(sweepmap({"eval", "--log", (dir / "nope.lcmlog").string(), "--rig", "rig_b", "--out",
                      (dir / "o").string()},
                     dir / "missing.txt"),
            0);
  EXPECT_NE(readFile(dir / "missing.txt").find("nope.lcmlog"), std::string::npos);
  EXPECT_EQ(sweepmap({"eval", "--experiment", "paper", "--rig", sourcePath("config/rig_b.yaml"),
                      "--scene", sourcePath("config/scene_lab.yaml"), "--set",
                      "odometry.no_such_key=1", "--out", (dir / "o").string()},
                     dir / "badkey.txt"),
            2);
  EXPECT_NE(readFile(dir / "badkey.txt").find("no_such_key"), std::string::npos)
      << readFile(dir / "badkey.txt");
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
