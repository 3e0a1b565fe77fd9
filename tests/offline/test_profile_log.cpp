// Rig C offline: the simulator is deterministic from its seed, a profile fits one datagram,
// and the log reader of the calibration names the log and event that cannot serve.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/event_log.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "tools/offline/profile_log.hpp"
#include "tools/offline/sim_profile.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

RotatingProfileConfig rigC(const std::vector<std::string>& sets = {}) {
  return loadRotatingProfileConfig(std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_c.yaml", sets);
}

std::string scratch(const std::string& name) {
  const fs::path d = fs::path(SWEEPMAP_BINARY_DIR) / "test_scratch" / "profile_log";
  fs::create_directories(d);
  return (d / name).string();
}

std::vector<Message> simulate(const RotatingProfileConfig& rig, uint64_t seed) {
  std::vector<Message> out;
  simulateRotatingProfile(rig, seed, [&](const Message& m) { out.push_back(m); });
  return out;
}

std::string errorOf(const std::string& path) {
  try {
    readProfileLog(path);
  } catch (const ProfileLogError& e) {
    return e.what();
  }
  return "";
}

TEST(ProfileSim, SameSeedSameMessagesOtherSeedOtherNoise) {
  const RotatingProfileConfig rig =
      rigC({"sim.plate_count=3", "turntable.sweep_start_deg=-5", "turntable.sweep_end_deg=5"});
  const auto a = simulate(rig, 7), b = simulate(rig, 7), c = simulate(rig, 8);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].channel, b[i].channel);
    ASSERT_EQ(a[i].utime, b[i].utime);
    ASSERT_EQ(a[i].data, b[i].data) << "message " << i;
  }
  bool differs = false;
  for (size_t i = 0; i < std::min(a.size(), c.size()); ++i) differs |= a[i].data != c[i].data;
  EXPECT_TRUE(differs);
  // The truth leads each sweep; profiles follow in time order.
  EXPECT_EQ(a.front().channel, channels::kTruthProfileRig);
  for (size_t i = 1; i < a.size(); ++i) EXPECT_LE(a[i - 1].utime, a[i].utime);
}

TEST(ProfileSim, AFullProfileFitsOneDatagram) {
  Profile p;
  p.column_count = 1280;
  p.counts_per_revolution = 262144;
  for (int i = 0; i < 1280; ++i) {
    p.column.push_back(static_cast<int16_t>(i));
    p.y_mm.push_back(0.1f * i);
    p.z_mm.push_back(-300.0f);
  }
  const profile_t m = toLcm(p);
  EXPECT_EQ(m.getEncodedSize(), 48 + 10 * 1280);  // as lcmtypes/profile_t.lcm says
  EXPECT_LT(m.getEncodedSize(), 65000);
  EXPECT_EQ(validateProfile(m), "");
}

TEST(ProfileLog, ReadsEverySweepAsAPlatePose) {
  const std::string path = scratch("plates.lcmlog");
  {
    EventLogWriter w(path);
    for (const Message& m :
         simulate(rigC({"turntable.sweep_start_deg=-5", "turntable.sweep_end_deg=5"}), 1)) {
      w.write(m.utime, m.channel, m.data);
    }
    w.close();
  }
  const ProfileLog log = readProfileLog(path);
  ASSERT_EQ(log.sweeps.size(), 3u);
  EXPECT_EQ(log.sweeps[1].source, path + " sweep 1");
  EXPECT_GT(log.sweeps[0].samples.size(), 10000u);
  ASSERT_TRUE(log.truth.has_value());
  EXPECT_DOUBLE_EQ(log.truth->geometry.m_mm, 123.0);
}

TEST(ProfileLog, TheTestPiecesTruthComesFromItsOwnChannel) {
  const std::string path = scratch("piece.lcmlog");
  {
    EventLogWriter w(path);
    for (const Message& m :
         simulate(rigC({"sim.scene=test_piece", "sim.test_piece.rect_length_mm=39.5",
                        "turntable.sweep_start_deg=-3", "turntable.sweep_end_deg=3"}),
                  1)) {
      w.write(m.utime, m.channel, m.data);
    }
    w.close();
  }
  const ProfileLog log = readProfileLog(path);
  ASSERT_TRUE(log.test_piece.has_value());
  EXPECT_DOUBLE_EQ(log.test_piece->sizes.rect_length_mm, 39.5);  // what the simulator used
  EXPECT_DOUBLE_EQ(log.test_piece->sizes.left_diameter_mm, 50.01);
  EXPECT_DOUBLE_EQ(log.test_piece->sizes.rect_depth_mm, 20.01);
  // Its frame: orthonormal, w up, the top face's centre under the sensor (300 mm down).
  const TestPieceTruth& t = *log.test_piece;
  EXPECT_NEAR(t.u.dot(t.v), 0.0, 1e-12);
  EXPECT_NEAR(t.w.z(), 1.0, 1e-12);
  EXPECT_NEAR(t.u.cross(t.v).dot(t.w), 1.0, 1e-12);
  EXPECT_NEAR(t.origin.z(), -300.0, 2.0);
  // A plate log has none.
  const std::string plates = scratch("plates_no_piece.lcmlog");
  {
    EventLogWriter w(plates);
    for (const Message& m :
         simulate(rigC({"turntable.sweep_start_deg=-3", "turntable.sweep_end_deg=3"}), 1)) {
      w.write(m.utime, m.channel, m.data);
    }
    w.close();
  }
  EXPECT_FALSE(readProfileLog(plates).test_piece.has_value());
}

TEST(ProfileLog, ALogWithoutProfilesIsAClearError) {
  const std::string path = scratch("no_profiles.lcmlog");
  {
    EventLogWriter w(path);
    w.write(1, "LIDAR_SCAN", std::vector<uint8_t>{1, 2, 3});
    w.close();
  }
  const std::string e = errorOf(path);
  EXPECT_NE(e.find(path), std::string::npos) << e;
  EXPECT_NE(e.find("no PROFILE messages"), std::string::npos) << e;
}

TEST(ProfileLog, ANonFiniteRangeNamesTheLogTheEventAndThePoint) {
  const std::string path = scratch("nan.lcmlog");
  Profile p;
  p.sequence = 41;
  p.column_count = 1280;
  p.counts_per_revolution = 262144;
  p.column = {10, 11};
  p.y_mm = {1.0f, 2.0f};
  p.z_mm = {-300.0f, std::numeric_limits<float>::quiet_NaN()};
  const profile_t m = toLcm(p);
  std::vector<uint8_t> bytes(m.getEncodedSize());
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  {
    EventLogWriter w(path);
    w.write(5, channels::kProfile, bytes);
    w.close();
  }
  const std::string e = errorOf(path);
  EXPECT_NE(e.find(path + ": PROFILE at byte 0 (sequence 41): point 1 (column 11)"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("not finite"), std::string::npos) << e;
}

TEST(ProfileLog, ATruncatedLogNamesItsOffset) {
  const std::string path = scratch("truncated.lcmlog");
  {
    EventLogWriter w(path);
    for (const Message& m : simulate(rigC({"sim.plate_count=1", "turntable.sweep_start_deg=-1",
                                           "turntable.sweep_end_deg=1"}),
                                     1)) {
      w.write(m.utime, m.channel, m.data);
    }
    w.close();
  }
  fs::resize_file(path, fs::file_size(path) - 100);
  const std::string e = errorOf(path);
  EXPECT_NE(e.find(path + ": byte "), std::string::npos) << e;
}

}  // namespace
}  // namespace sweepmap
