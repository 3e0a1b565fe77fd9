// Rig C end to end through the binary: `sweepmap sim --rig rig_c` is deterministic from its
// seed, and `sweepmap calib axis-offset` calibrates from its log, writes the file the rig
// points to and the S(M, N) figure, and refuses bad input with a clear message.
#include <gtest/gtest.h>

#include <fstream>

#include "core/calibration_file.hpp"
#include "tests/e2e/test_support.hpp"

namespace sweepmap {
namespace test {
namespace {

TEST(SimRigC, SameSeedIsByteIdenticalForBothScenes) {
  const auto dir = scratchDir("sim_rig_c");
  for (const char* scene : {"plate", "test_piece"}) {
    const std::string s(scene);
    for (const char* name : {"a", "b"}) {
      ASSERT_EQ(sweepmap({"sim", "--rig", "rig_c", "--scene", s, "--seed", "3", "--out",
                          (dir / (s + name + ".lcmlog")).string()},
                         dir / (s + name + ".txt")),
                0)
          << readFile(dir / (s + name + ".txt"));
    }
    const std::string a = readFile(dir / (s + "a.lcmlog"));
    EXPECT_GT(a.size(), 1000000u) << scene;
    EXPECT_TRUE(a == readFile(dir / (s + "b.lcmlog"))) << scene << ": logs differ";
    EXPECT_FALSE(readChannel((dir / (s + "a.lcmlog")).string(), "PROFILE").empty());
    EXPECT_FALSE(readChannel((dir / (s + "a.lcmlog")).string(), "TRUTH_PROFILE_RIG").empty());
  }
  ASSERT_EQ(
      sweepmap({"sim", "--rig", "rig_c", "--seed", "4", "--out", (dir / "c.lcmlog").string()}), 0);
  EXPECT_FALSE(readFile(dir / "platea.lcmlog") == readFile(dir / "c.lcmlog"));
  // A scene file is not a rig C scene.
  EXPECT_EQ(sweepmap({"sim", "--rig", "rig_c", "--scene", "scene_lab", "--out",
                      (dir / "x.lcmlog").string()},
                     dir / "bad_scene.txt"),
            2);
  EXPECT_NE(readFile(dir / "bad_scene.txt").find("plate or test_piece"), std::string::npos);
}

TEST(ToolRigC, CalibAxisOffsetFromASimulatedLog) {
  const std::string log = cachedSimLog("rig_c_plates", {"--rig", "rig_c", "--seed", "1"});
  const auto dir = scratchDir("calib_axis_offset");
  const auto out = dir / "axis_offset.yaml";
  ASSERT_EQ(sweepmap({"calib", "axis-offset", "--logs", log, "--rig", "rig_c", "--out",
                      out.string(), "--json"},
                     dir / "calib.txt"),
            0)
      << readFile(dir / "calib.txt");
  const std::string text = readFile(dir / "calib.txt");
  const auto json = nlohmann::json::parse(text.substr(text.find('{'), text.rfind('}') + 1));
  EXPECT_LT(std::fabs(json["offset_error_mm"]["ours"]["M"].get<double>()), 0.1) << json.dump(2);
  EXPECT_LT(std::fabs(json["offset_error_mm"]["ours"]["N"].get<double>()), 0.1);
  EXPECT_EQ(json["paper"]["evaluations"].get<int>(), 21 * 31);
  EXPECT_TRUE(fs::exists(dir / "axis_offset_S.png"));
  const AxisOffsetCalibration c = loadAxisOffsetCalibration(out.string());
  EXPECT_NEAR(c.m_mm, 123.0, 0.1);
  EXPECT_NEAR(c.n_mm, 409.0, 0.1);
  EXPECT_EQ(c.logs, std::vector<std::string>{log});
  // A log without profiles: bad input (exit 1), naming it.
  const std::string rig_a_log = (dir / "rig_a.lcmlog").string();
  { std::ofstream(rig_a_log) << ""; }
  EXPECT_EQ(sweepmap({"calib", "axis-offset", "--logs", rig_a_log, "--rig", "rig_c", "--out",
                      (dir / "x.yaml").string()},
                     dir / "empty.txt"),
            1);
  EXPECT_NE(readFile(dir / "empty.txt").find(rig_a_log + ": no PROFILE messages"),
            std::string::npos)
      << readFile(dir / "empty.txt");
  // A kind axis-offset does not serve (rig A's is the lidar's offset: test_axis_offset_lidar).
  EXPECT_EQ(sweepmap({"calib", "axis-offset", "--logs", log, "--rig", "rig_b", "--out",
                      (dir / "x.yaml").string()},
                     dir / "kind.txt"),
            2);
  EXPECT_NE(readFile(dir / "kind.txt").find("needs a rotating_profile rig"), std::string::npos);
}

TEST(ReplayRigC, CloudByEq7LiesOnThePlatesWithTheTrueGeometry) {
  const std::string log = cachedSimLog("rig_c_plates", {"--rig", "rig_c", "--seed", "1"});
  const auto dir = scratchDir("replay_rig_c");
  const std::vector<std::string> truth = {
      "--set", "geometry.offset_m_mm=123",    "--set", "geometry.offset_n_mm=409",
      "--set", "geometry.laser_tilt_deg=0.2", "--set", "geometry.encoder_zero_deg=0.5"};
  std::vector<std::string> args = {"replay", log,     "--rig",
                                   "rig_c",  "--out", (dir / "truth").string()};
  args.insert(args.end(), truth.begin(), truth.end());
  ASSERT_EQ(sweepmap(args, dir / "truth.txt"), 0) << readFile(dir / "truth.txt");
  ASSERT_EQ(sweepmap({"replay", log, "--rig", "rig_c", "--out", (dir / "nominal").string()}), 0);
  const auto summary = readJson(dir / "truth" / "summary.json");
  EXPECT_EQ(summary["sweeps"].size(), 3u);
  EXPECT_GT(summary["points"].get<int64_t>(), 1000000);
  EXPECT_EQ(summary["invalid_profiles"].get<int>(), 0);
  for (int k = 0; k < 3; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "sweeps/sweep_%06d.pcd", k);
    const double with_truth = rmsToTruePlane(log, dir / "truth" / name, k);
    const double with_nominal = rmsToTruePlane(log, dir / "nominal" / name, k);
    std::printf("sweep %d: RMS to the true plane %.4f mm (true geometry), %.3f mm (nominal)\n", k,
                with_truth, with_nominal);
    EXPECT_LT(with_truth, 0.05) << k;               // range noise 0.02 mm, encoder quantisation
    EXPECT_GT(with_nominal, 10 * with_truth) << k;  // 3 mm off: the plates bend
  }
  EXPECT_TRUE(fs::exists(dir / "truth" / "cloud.pcd"));
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
