// `sweepmap import breezyslam` on the real recording in ../shared (skipped without it).
#include <gtest/gtest.h>

#include <fstream>

#include "processes/channels.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"
#include "tests/e2e/test_support.hpp"
#include "tools/import/import_mines.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kData = std::string(SWEEPMAP_SHARED_DIR) + "/data/real/breezyslam_exp2.dat";

TEST(ImportBreezySlam, RealRecordingBecomesRawMessages) {
  if (!fs::exists(kData))
    GTEST_SKIP() << kData << " not present (../shared is not beside this checkout)";
  const auto dir = scratchDir("import_breezyslam");
  const std::string log = (dir / "exp2.lcmlog").string();
  ASSERT_EQ(sweepmap({"import", "breezyslam", kData, "--out", log}, dir / "out.txt"), 0)
      << readFile(dir / "out.txt");
  const auto scans = readChannel(log, channels::kLidarScan);
  const auto wheels = readChannel(log, channels::kWheelTicks);
  ASSERT_EQ(scans.size(), 641u);
  ASSERT_EQ(wheels.size(), 641u);
  lidar_scan_t s;
  ASSERT_TRUE(decodeMessage(scans.front(), &s));
  EXPECT_EQ(s.nranges, 682);
  EXPECT_EQ(s.utime, 361431443);  // the original timestamp
  wheel_ticks_t w;
  ASSERT_TRUE(decodeMessage(wheels.front(), &w));
  EXPECT_EQ(w.left_ticks, 234835);
  EXPECT_EQ(w.right_ticks, 231727);
  int64_t last = 0;
  for (const auto& m : scans) {
    ASSERT_TRUE(decodeMessage(m, &s));
    EXPECT_GT(s.utime, last);
    last = s.utime;
  }
}

TEST(ImportBreezySlam, MalformedLineNamesFileLineAndToken) {
  const auto dir = scratchDir("import_bad");
  {
    std::ofstream f(dir / "bad.dat");
    std::string good = "100 0 5 6";
    for (int i = 4; i < 24; ++i) good += " 0";
    for (int i = 0; i < 10; ++i) good += " 1000";
    good += " 0\n";
    f << good;
    std::string bad = good;
    bad.replace(0, 3, "200");
    bad.replace(bad.find(" 1000"), 5, " 10x0");
    f << bad;
  }
  try {
    importBreezySlam((dir / "bad.dat").string(), (dir / "bad.lcmlog").string());
    FAIL() << "malformed line accepted";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bad.dat:2"), std::string::npos) << what;
    EXPECT_NE(what.find("token 25"), std::string::npos) << what;
  }
  // The good first line was kept.
  EXPECT_EQ(readChannel((dir / "bad.lcmlog").string(), channels::kLidarScan).size(), 1u);
}

}  // namespace
}  // namespace test
}  // namespace sweepmap

namespace sweepmap {
namespace test {
namespace {

// The imported recording through sweepmap-odometry's EKF (wheels alone: no IMU on this
// robot), the world-frame assembler and the mapper.
TEST(ReplayMobile, BreezySlamRecordingBecomesAMap) {
  if (!fs::exists(kData))
    GTEST_SKIP() << kData << " not present (../shared is not beside this checkout)";
  const auto dir = scratchDir("replay_mobile");
  const std::string log = (dir / "exp2.lcmlog").string();
  ASSERT_EQ(sweepmap({"import", "breezyslam", kData, "--out", log}), 0);
  const std::string rig = sourcePath("config/rig_b_mines_rover.yaml");
  for (const char* out : {"a", "b"}) {
    ASSERT_EQ(sweepmap({"replay", log, "--rig", rig, "--out", (dir / out).string()},
                       dir / (std::string(out) + ".txt")),
              0)
        << readFile(dir / (std::string(out) + ".txt"));
  }
  const auto s = readJson(dir / "a" / "summary.json");
  EXPECT_GE(s["scans"].get<int>(), 630);
  EXPECT_GT(s["points"].get<int>(), 100000);
  EXPECT_EQ(s["odometry"]["gyro_fused"].get<int>(), 0);
  // Wheels alone: the EKF follows the wheel odometry.
  const double ekf = s["odometry"]["path_length_m_ekf"].get<double>();
  const double wheels = s["odometry"]["path_length_m_wheels"].get<double>();
  EXPECT_GT(wheels, 10.0);
  EXPECT_NEAR(ekf, wheels, 0.02 * wheels);
  EXPECT_GT(s["map"]["occupied_voxels"].get<int>(), 1000);
  EXPECT_TRUE(fs::exists(dir / "a" / "top_view.png"));
  // Deterministic.
  for (const char* f : {"map.bt", "cloud.pcd", "summary.json", "derived.lcmlog"}) {
    EXPECT_TRUE(readFile(dir / "a" / f) == readFile(dir / "b" / f)) << f;
  }
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
