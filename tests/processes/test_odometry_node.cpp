#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/calibration_file.hpp"
#include "core/config.hpp"
#include "processes/channels.hpp"
#include "processes/odometry_node.hpp"
#include "rigs/mobile_lidar.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"

namespace sweepmap {
namespace {

template <class T>
Message encode(const std::string& ch, const T& m) {
  Outbox o;
  o.publish(ch, 0, m);
  return o.take().front();
}

Message ticks(int64_t utime, int64_t left, int64_t right) {
  wheel_ticks_t m;
  m.utime = utime;
  m.left_ticks = left;
  m.right_ticks = right;
  return encode(channels::kWheelTicks, m);
}

Message gyro(int64_t utime, double wz) {
  imu_t m{};
  m.utime = utime;
  m.gyro_rad_s[2] = wz;
  return encode(channels::kImu, m);
}

std::vector<pose2d_t> run(OdometryNode& node, const std::vector<Message>& msgs,
                          const std::string& channel) {
  std::vector<pose2d_t> out;
  for (const auto& m : msgs) {
    Outbox o;
    node.receive(m, o);
    for (const auto& r : o.take()) {
      pose2d_t p{};
      if (r.channel == channel && decodeMessage(r, &p)) out.push_back(p);
    }
  }
  return out;
}

OdometryConfig config() {
  OdometryConfig c;
  c.wheel_radius_m = 0.1;
  c.ticks_per_revolution = 1000;
  c.ekf.wheel_distance_m = 0.3;
  return c;
}

TEST(OdometryNode, StraightDriveFromTicks) {
  OdometryNode node(config());
  std::vector<Message> msgs;
  // 0.2 m/s: 2 pi 0.1 m per 1000 ticks -> 318.3 ticks/s; 20 ms steps.
  for (int k = 0; k <= 250; ++k) {
    const int64_t t = 1000000 + 20000 * k;
    const int64_t n = std::llround(318.30988618 * 0.02 * k);
    msgs.push_back(ticks(t, n, n));
    msgs.push_back(gyro(t + 5000, 0.0));
  }
  const auto odo = run(node, msgs, channels::kWheelOdometry);
  ASSERT_EQ(odo.size(), 250u);
  EXPECT_NEAR(odo.back().x_m, 1.0, 0.01);  // 5 s at 0.2 m/s
  EXPECT_NEAR(odo.back().y_m, 0.0, 1e-9);
  EXPECT_EQ(node.ekf().counters().wheels, 250);
  EXPECT_NEAR(node.ekf().pose().x_m, 1.0, 0.02);
}

TEST(OdometryNode, BadInputRejectedAndCounted) {
  OdometryNode node(config());
  std::vector<Message> msgs = {ticks(1000000, 0, 0),
                               ticks(1020000, 5, 5),
                               ticks(1010000, 6, 6),         // back in time
                               ticks(1040000, 100000, 5),    // absurd jump
                               gyro(1050000, std::nan("")),  // NaN rate
                               gyro(1050000, 1e6),           // absurd rate
                               Message{0, channels::kWheelTicks, {1, 2, 3}},
                               ticks(1060000, 100010, 15)};
  run(node, msgs, channels::kOdometryPose);
  EXPECT_EQ(node.counter("invalid"), 3);
  EXPECT_EQ(node.counter("gyro_rejected"), 2);
  EXPECT_EQ(node.ekf().counters().invalid, 2);
  EXPECT_TRUE(node.ekf().state().allFinite());
}

TEST(OdometryNode, ShippedConfigLoads) {
  const OdometryConfig c =
      loadMobileLidarConfig(std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b_mines_rover.yaml")
          .odometry;
  EXPECT_DOUBLE_EQ(c.wheel_radius_m, 0.077);
  EXPECT_FALSE(c.use_imu);
}

// mounting.calibration_file (relative to the rig file) replaces the rig's gamma/beta/alpha_rad.
TEST(MobileLidarConfig, MountingCalibrationFileReplacesTheAngles) {
  namespace fs = std::filesystem;
  const fs::path dir_ = fs::temp_directory_path() / "sweepmap_rig_b_mounting_file";
  fs::remove_all(dir_);
  fs::create_directories(dir_);
  MountingCalibration c;
  c.gamma_rad = 0.0355123456789;
  c.beta_rad = 0.0126;
  c.alpha_rad = -0.0058;
  writeMountingCalibration((dir_ / "mounting.yaml").string(), c);
  std::ifstream in(std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string rig = text.str();
  const std::string from = "calibration_file: \"\"";
  ASSERT_NE(rig.find(from), std::string::npos);
  rig.replace(rig.find(from), from.size(), "calibration_file: mounting.yaml");
  std::ofstream(dir_ / "rig_b.yaml") << rig;
  const MobileLidarConfig b = loadMobileLidarConfig((dir_ / "rig_b.yaml").string());
  EXPECT_NEAR(b.mounting.gamma_rad, c.gamma_rad, 1e-12);
  EXPECT_DOUBLE_EQ(b.mounting.beta_rad, c.beta_rad);
  EXPECT_DOUBLE_EQ(b.mounting.alpha_rad, c.alpha_rad);
  // Without it the rig's own values stay.
  EXPECT_DOUBLE_EQ(loadMobileLidarConfig(std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b.yaml")
                       .mounting.gamma_rad,
                   0.0);
  fs::remove(dir_ / "mounting.yaml");
  try {
    loadMobileLidarConfig((dir_ / "rig_b.yaml").string());
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("mounting.yaml"), std::string::npos) << e.what();
  }
  fs::remove_all(dir_);
}

}  // namespace
}  // namespace sweepmap
