#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "core/calibration_file.hpp"
#include "core/config.hpp"
#include "processes/channels.hpp"
#include "processes/odometry_node.hpp"
#include "processes/sim_car.hpp"
#include "rigs/mobile_lidar.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "sweepmap/wheel_cmd_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"
#include "tests/processes/node_test_util.hpp"
#include "tests/sim/hand_scene.hpp"

namespace sweepmap {
namespace {

using test::encode;

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

// Issue 21: one IMU message stamped a day ahead moved the EKF to x = -8.5e6 m, and one such
// WHEEL_TICKS froze that channel until restart. Now neither reaches the node, the drive goes
// on as without them, and both are counted with their offset.
TEST(OdometryNode, AMessageStampedADayAheadNeitherMovesTheEstimateNorFreezesItsChannel) {
  constexpr int64_t kDay = 86'400'000'000;
  auto arriving = [](Message m, int64_t arrival_us) {
    m.utime = arrival_us;
    return m;
  };
  auto drive = [&](bool poisoned) {
    OdometryNode node(config());
    std::vector<Message> msgs;
    for (int k = 0; k <= 100; ++k) {
      const int64_t t = 1000000 + 20000 * k;
      const int64_t n = std::llround(318.30988618 * 0.02 * k);
      msgs.push_back(arriving(ticks(t, n, n), t + 1000));
      msgs.push_back(arriving(gyro(t + 5000, 0.01), t + 6000));
      if (poisoned && k == 50) {  // both arrive now
        msgs.push_back(arriving(gyro(t + 6000 + kDay, 5.0), t + 6500));
        msgs.push_back(arriving(ticks(t + 7000 + kDay, n + 100000, n), t + 7500));
      }
    }
    run(node, msgs, channels::kOdometryPose);
    return std::make_pair(node.ekf().pose(),
                          std::make_pair(node.counter("stamp_refused_IMU"),
                                         node.counter("stamp_refused_WHEEL_TICKS")));
  };
  const auto [clean, clean_refused] = drive(false);
  const auto [poisoned, refused] = drive(true);
  EXPECT_EQ(clean_refused, std::make_pair(int64_t{0}, int64_t{0}));
  EXPECT_EQ(refused, std::make_pair(int64_t{1}, int64_t{1}));
  EXPECT_DOUBLE_EQ(poisoned.x_m, clean.x_m);
  EXPECT_DOUBLE_EQ(poisoned.y_m, clean.y_m);
  EXPECT_DOUBLE_EQ(poisoned.theta_rad, clean.theta_rad);
  EXPECT_NEAR(clean.x_m, 0.4, 0.01);  // 2 s at 0.2 m/s: later ticks were not frozen out
}

// Issue 21: the EKF must not say `trusted` while its input is being refused. After a day-ahead
// IMU or WHEEL_TICKS message (refused by the stamp guard), the poses say trusted = false and
// the status DEGRADED, naming the channel, until good input has covered
// odometry.refused_input_window_s (2 s) of message time; then trusted and OK again.
TEST(OdometryNode, RefusedInputMakesPosesUntrustedAndStatusDegradedUntilGoodInputFlows) {
  constexpr int64_t kDay = 86'400'000'000;
  constexpr int64_t kRefusedAt = 2'000'000;  // k = 50
  for (const std::string channel : {channels::kImu, channels::kWheelTicks}) {
    OdometryNode node(config());
    std::vector<std::pair<int64_t, bool>> poses;  // stamp, trusted
    std::vector<std::pair<int64_t, process_status_t>> statuses;
    auto deliver = [&](Message m, int64_t arrival) {
      m.utime = arrival;
      Outbox o;
      node.receive(m, o);
      node.tick(arrival, o);
      node.publishStatus(arrival, o);
      for (const auto& r : o.take()) {
        pose2d_t p{};
        process_status_t s;
        if (r.channel == channels::kOdometryPose && decodeMessage(r, &p)) {
          poses.emplace_back(p.utime, p.trusted);
        }
        if (r.channel == node.statusChannel() && decodeMessage(r, &s)) {
          statuses.emplace_back(arrival, s);
        }
      }
    };
    for (int k = 0; k <= 250; ++k) {
      const int64_t t = 1'000'000 + 20'000 * k;
      const int64_t n = std::llround(318.30988618 * 0.02 * k);
      deliver(ticks(t, n, n), t + 1000);
      deliver(gyro(t + 5000, 0.01), t + 6000);
      if (t == kRefusedAt) {
        deliver(channel == channels::kImu ? gyro(t + kDay, 5.0) : ticks(t + kDay, n + 9999, n),
                t + 7000);
      }
    }
    EXPECT_EQ(node.counter("stamp_refused_" + channel), 1) << channel;
    EXPECT_EQ(node.counter("refused_input"), 1) << channel;
    for (const auto& [stamp, trusted] : poses) {
      const bool in_window = stamp >= kRefusedAt && stamp < kRefusedAt + 2'000'000;
      EXPECT_EQ(trusted, !in_window) << channel << " pose at " << stamp;
    }
    for (const auto& [arrival, s] : statuses) {
      if (arrival < kRefusedAt) {
        EXPECT_EQ(s.health, +process_status_t::OK) << arrival;
      }
      if (arrival > kRefusedAt + 7000 && arrival < kRefusedAt + 1'900'000) {
        EXPECT_EQ(s.health, +process_status_t::DEGRADED) << channel << " " << arrival;
        EXPECT_NE(s.detail.find(channel + " input refused"), std::string::npos) << s.detail;
      }
      if (arrival > kRefusedAt + 2'100'000) {
        EXPECT_EQ(s.health, +process_status_t::OK) << channel << " " << arrival << " " << s.detail;
      }
    }
  }
}

// The EKF's covariance says when its poses are not to be trusted (heading sigma over
// odometry.trusted_theta_sigma_rad): then the status is DEGRADED too.
TEST(OdometryNode, UntrustedCovarianceDegradesTheStatus) {
  OdometryConfig c = config();
  c.ekf.trusted_theta_sigma_rad = 1e-9;  // any heading uncertainty is too much
  OdometryNode node(c);
  Outbox o;
  for (int k = 0; k < 20; ++k) {
    Message m = ticks(1'000'000 + 20'000 * k, 10 * k, 10 * k);
    m.utime = 1'001'000 + 20'000 * k;
    node.receive(m, o);
  }
  node.tick(1'500'000, o);
  node.publishStatus(1'500'000, o);
  process_status_t s;
  bool untrusted = false;
  for (const auto& r : o.take()) {
    pose2d_t p{};
    if (r.channel == channels::kOdometryPose && decodeMessage(r, &p)) untrusted |= !p.trusted;
    if (r.channel == node.statusChannel()) {
      ASSERT_TRUE(decodeMessage(r, &s));
    }
  }
  EXPECT_TRUE(untrusted);
  EXPECT_EQ(s.health, +process_status_t::DEGRADED);
  EXPECT_NE(s.detail.find("trusted_theta_sigma_rad"), std::string::npos) << s.detail;
}

TEST(OdometryNode, BadInputRejectedAndCounted) {
  OdometryNode node(config());
  std::vector<Message> msgs = {ticks(1000000, 0, 0),
                               ticks(1020000, 5, 5),
                               ticks(1010000, 6, 6),         // back in time
                               ticks(1040000, 100000, 5),    // absurd jump
                               gyro(1050000, std::nan("")),  // NaN rate: not an imu_t
                               gyro(1050000, 1e6),           // absurd rate
                               Message{0, channels::kWheelTicks, {1, 2, 3}},
                               ticks(1060000, 100010, 15)};
  run(node, msgs, channels::kOdometryPose);
  // The NaN rate and the 3 bytes never reach the node (their type's schema refuses them,
  // per channel); the jumps and the absurd rate are the node's own checks.
  EXPECT_EQ(node.counter("invalid_IMU"), 1);
  EXPECT_EQ(node.counter("invalid_WHEEL_TICKS"), 1);
  EXPECT_EQ(node.counter("invalid"), 4);
  EXPECT_EQ(node.counter("gyro_rejected"), 1);
  EXPECT_EQ(node.ekf().counters().invalid, 1);
  EXPECT_TRUE(node.ekf().state().allFinite());
}

// Scripted devices: samples handed out once their time has come; the IMU can go silent.
class ScriptedImu : public ImuDevice {
 public:
  std::vector<ImuSample> samples;
  int64_t silent_from = INT64_MAX, silent_to = INT64_MAX;
  std::vector<ImuSample> poll(int64_t now) override {
    std::vector<ImuSample> out;
    for (; next_ < samples.size() && samples[next_].utime <= now; ++next_) {
      const int64_t t = samples[next_].utime;
      if (t < silent_from || t >= silent_to) out.push_back(samples[next_]);
    }
    return out;
  }

 private:
  size_t next_ = 0;
};

class ScriptedWheels : public WheelDevice {
 public:
  std::vector<WheelTicks> ticks;
  std::vector<std::pair<double, double>> commands;
  std::vector<WheelTicks> poll(int64_t now) override {
    std::vector<WheelTicks> out;
    for (; next_ < ticks.size() && ticks[next_].utime <= now; ++next_) out.push_back(ticks[next_]);
    return out;
  }
  void command(int64_t, double v, double w) override { commands.emplace_back(v, w); }

 private:
  size_t next_ = 0;
};

// A turning drive: wheels at 50 Hz, the gyro at 200 Hz (0.2 m/s, 0.4 rad/s).
void script(ScriptedImu* imu, ScriptedWheels* wheels, int64_t t0, double seconds) {
  const double ticks_per_m = 1000.0 / (2 * M_PI * 0.1), v = 0.2, w = 0.4, b = 0.3;
  for (int64_t k = 0; k * 20000 <= seconds * 1e6; ++k) {
    const double t = k * 0.02;
    wheels->ticks.push_back({t0 + k * 20000, std::llround((v - w * b / 2) * t * ticks_per_m),
                             std::llround((v + w * b / 2) * t * ticks_per_m), 0});
  }
  for (int64_t k = 0; k * 5000 <= seconds * 1e6; ++k) {
    ImuSample s{};
    s.utime = t0 + 2500 + k * 5000;
    s.gyro[2] = w;
    s.accel[2] = 9.81;
    s.rpy[0] = s.rpy[1] = s.rpy[2] = std::nan("");
    imu->samples.push_back(s);
  }
}

// Live with devices: the node publishes the devices' raw messages first, in time order, then its
// poses; a node without devices fed those raw messages (a replay of the recorded log) publishes
// the same poses, byte for byte.
TEST(OdometryNode, DevicesModePublishesRawFirstAndEqualsReplay) {
  ScriptedImu imu;
  ScriptedWheels wheels;
  const int64_t t0 = 1'000'000;
  script(&imu, &wheels, t0, 4.0);
  OdometryNode live(config(), &imu, &wheels);
  EXPECT_EQ(live.subscriptions(), std::vector<std::string>{channels::kWheelCmd});
  std::vector<Message> published;
  for (int64_t now = t0; now <= t0 + 4'100'000; now += 10'000) {  // the process's 10 ms tick
    Outbox o;
    live.tick(now, o);
    for (auto& m : o.take()) published.push_back(std::move(m));
  }
  std::vector<Message> raw, poses;
  int64_t last_raw = INT64_MIN;
  for (const auto& m : published) {
    if (m.channel == channels::kImu || m.channel == channels::kWheelTicks) {
      raw.push_back(m);
      EXPECT_GE(m.utime, last_raw);
      last_raw = m.utime;
    } else if (m.channel == channels::kOdometryPose || m.channel == channels::kWheelOdometry) {
      poses.push_back(m);
    }
  }
  EXPECT_EQ(raw.size(), imu.samples.size() + wheels.ticks.size());
  ASSERT_EQ(poses.size(), 2 * (wheels.ticks.size() - 1));

  OdometryNode replay(config());
  std::vector<Message> replayed;
  for (const auto& m : raw) {
    Outbox o;
    replay.receive(m, o);
    for (auto& r : o.take()) {
      if (r.channel == channels::kOdometryPose || r.channel == channels::kWheelOdometry) {
        replayed.push_back(std::move(r));
      }
    }
  }
  ASSERT_EQ(replayed.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(replayed[i].channel, poses[i].channel) << i;
    EXPECT_TRUE(replayed[i].data == poses[i].data) << i;
  }
  pose2d_t end{};
  ASSERT_TRUE(decodeMessage(poses.back(), &end));
  // 4-5 counts per wheel per reading: their quantisation is part of the speeds' noise, not
  // slip (no reading gated, the gyro's bias not pulled).
  EXPECT_EQ(live.ekf().counters().gated_wheels, 0);
  EXPECT_NEAR(live.ekf().state()[OdometryEkf::kBias], 0.0, 1e-3);
  EXPECT_NEAR(end.theta_rad, std::remainder(0.4 * 4.0, 2 * M_PI), 0.01);
}

// WHEEL_CMD goes to the wheel board; a malformed or absurd one is counted, not sent.
TEST(OdometryNode, WheelCommandsGoToTheBoard) {
  ScriptedImu imu;
  ScriptedWheels wheels;
  OdometryNode node(config(), &imu, &wheels);
  wheel_cmd_t c{};
  c.utime = 5;
  c.v_m_s = 0.3;
  c.w_rad_s = -0.2;
  Outbox o;
  node.receive(encode(channels::kWheelCmd, c), o);
  c.v_m_s = std::nan("");
  node.receive(encode(channels::kWheelCmd, c), o);
  node.receive(Message{0, channels::kWheelCmd, {1, 2}}, o);
  ASSERT_EQ(wheels.commands.size(), 1u);
  EXPECT_EQ(wheels.commands[0], std::make_pair(0.3, -0.2));
  EXPECT_EQ(node.counter("invalid"), 2);
}

// The IMU goes silent for 2 s while the wheels go on: the status turns DEGRADED ("EKF on wheels
// alone") 0.5 s in, poses go on from the wheels, and when the samples return the status is OK
// again; one outage counted.
TEST(OdometryNode, ImuOutageDegradesAndRecovers) {
  ScriptedImu imu;
  ScriptedWheels wheels;
  const int64_t t0 = 1'000'000;
  script(&imu, &wheels, t0, 6.0);
  imu.silent_from = t0 + 2'000'000;
  imu.silent_to = t0 + 4'000'000;
  OdometryNode node(config(), &imu, &wheels);
  std::vector<std::pair<int64_t, process_status_t>> statuses;
  size_t poses_in_outage = 0;
  for (int64_t now = t0; now <= t0 + 6'000'000; now += 10'000) {
    Outbox o;
    node.tick(now, o);
    if (now % 250'000 == 0) node.publishStatus(now, o);
    for (const auto& m : o.take()) {
      process_status_t s;
      if (m.channel == node.statusChannel() && decodeMessage(m, &s)) statuses.emplace_back(now, s);
      poses_in_outage += m.channel == channels::kOdometryPose && now > imu.silent_from + 600'000 &&
                         now < imu.silent_to;
    }
  }
  EXPECT_GT(poses_in_outage, 50u);
  bool degraded = false, ok_after = false, ok_before = false;
  for (const auto& [now, s] : statuses) {
    if (now < imu.silent_from) ok_before = s.health == process_status_t::OK;
    if (now > imu.silent_from + 600'000 && now < imu.silent_to) {
      degraded = s.health == process_status_t::DEGRADED &&
                 s.detail.find("EKF on wheels alone") != std::string::npos;
      EXPECT_TRUE(degraded) << now << ": " << s.detail;
    }
    if (now > imu.silent_to + 100'000) ok_after = s.health == process_status_t::OK;
  }
  EXPECT_TRUE(ok_before);
  EXPECT_TRUE(degraded);
  EXPECT_TRUE(ok_after);
  EXPECT_EQ(node.counter("imu_outages"), 1);
}

// Two devices, two clocks: the IMU's samples fall anywhere within the wheel board's 20 ms
// intervals. A 0.4 s slip of the left wheel (20 % fast) must be gated whatever that phase. (The
// EKF used to gate the wheels on its predicted turn rate alone, which spreads quickly between
// gyro samples: the slip was gated when a gyro sample shared the wheel reading's mid-time, as
// in the simulator, and fused, the gyro gated instead, when the IMU's stamps were a fraction
// of a millisecond later, as with the emulated devices.)
TEST(OdometryNode, SlipIsGatedWhateverThePhaseOfImuAndWheels) {
  OdometryConfig c = config();
  c.ticks_per_revolution = 100000;  // fine counts: the test is about the gate, not quantisation
  const double per_tick = 2.0 * M_PI * c.wheel_radius_m / c.ticks_per_revolution;
  const double v = 0.2, w = 0.24, wd = c.ekf.wheel_distance_m, bias = 0.01;
  for (const int64_t phase_us : {0, 500, 1000, 2000, 2500, 3000, 4000, 4500, 4900}) {
    OdometryNode node(c);
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0.0, 0.005);
    std::vector<std::pair<int64_t, Message>> timed;
    double left_m = 0.0, right_m = 0.0;
    const int64_t t0 = 1000000;
    for (int k = 0; k <= 500; ++k) {  // 10 s of wheel readings at 50 Hz
      const int64_t t = t0 + 20000 * k;
      if (k > 0) {
        const bool slipping = t > t0 + 5000000 && t <= t0 + 5400000;
        left_m += (v - 0.5 * w * wd) * 0.02 * (slipping ? 1.2 : 1.0);
        right_m += (v + 0.5 * w * wd) * 0.02;
      }
      timed.emplace_back(
          t, ticks(t, std::llround(left_m / per_tick), std::llround(right_m / per_tick)));
    }
    for (int64_t t = t0 + phase_us; t <= t0 + 10000000; t += 5000) {  // 200 Hz gyro
      timed.emplace_back(t, gyro(t, w + bias + noise(rng)));
    }
    std::stable_sort(timed.begin(), timed.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<Message> msgs;
    for (auto& [t, m] : timed) msgs.push_back(std::move(m));
    run(node, msgs, channels::kOdometryPose);
    const auto& n = node.ekf().counters();
    // 20 readings slip; up to 0.2 s after it the slip test's longer window still holds it.
    EXPECT_GE(n.gated_wheels, 15) << "phase " << phase_us << " us";
    EXPECT_LE(n.gated_wheels, 32) << "phase " << phase_us << " us";
    EXPECT_LE(n.gated_gyro, 2) << "phase " << phase_us << " us";
    EXPECT_NEAR(node.ekf().pose().theta_rad, w * 10.0, 0.01) << "phase " << phase_us << " us";
  }
}

TEST(OdometryNode, ShippedConfigLoads) {
  const OdometryConfig c =
      loadMobileLidarConfig(std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b_mines_rover.yaml")
          .odometry;
  EXPECT_DOUBLE_EQ(c.wheel_radius_m, 0.077);
  EXPECT_FALSE(c.use_imu);
}

// A new empty folder under the temporary directory.
std::filesystem::path emptyTempDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// mounting.calibration_file (relative to the rig file) replaces the rig's gamma/beta/alpha_rad.
TEST(MobileLidarConfig, MountingCalibrationFileReplacesTheAngles) {
  namespace fs = std::filesystem;
  const fs::path dir_ = emptyTempDir("sweepmap_rig_b_mounting_file");
  MountingCalibration c;
  c.gamma_rad = 0.0355123456789;
  c.beta_rad = 0.0126;
  c.alpha_rad = -0.0058;
  writeMountingCalibration((dir_ / "mounting.yaml").string(), c);
  std::ifstream in(std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string rig = text.str();
  const std::string from = "  calibration_file: \"\"";  // mounting's, not the top-level one
  ASSERT_NE(rig.find(from), std::string::npos);
  rig.replace(rig.find(from), from.size(), "  calibration_file: mounting.yaml");
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

// The top-level calibration_file (sweepmap calib rig's) replaces any key it holds, the new
// rig B keys among them; the simulated car stays the one the rig file describes (its own
// wheels and lidar position plus the sim.* errors), so a calibrated rig file simulates the
// car it was calibrated on.
TEST(MobileLidarConfig, RigCalibrationFileReplacesItsKeysButNotTheSimulatedCar) {
  const std::filesystem::path dir = emptyTempDir("sweepmap_rig_b_rig_calibration");
  RigCalibrationFile f;
  f.parameters = {{"mounting.x_m", 0.1031},
                  {"odometry.wheel_radius_m", 0.0328},
                  {"odometry.wheel_radius_right_m", 0.0321},
                  {"odometry.wheel_distance_m", 0.204},
                  {"lidar.time_offset_s", 0.003},
                  {"odometry.gyro_bias_rad_s", 0.01}};
  writeRigCalibration((dir / "rig_calibration.yaml").string(), f);
  const std::string rig_b = std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b.yaml";
  const MobileLidarConfig plain = loadMobileLidarConfig(rig_b);
  const MobileLidarConfig c =
      loadMobileLidarConfig(rig_b, {"calibration_file=" + (dir / "rig_calibration.yaml").string()});
  EXPECT_DOUBLE_EQ(c.mounting.x_m, 0.1031);
  EXPECT_DOUBLE_EQ(c.odometry.wheel_radius_m, 0.0328);
  EXPECT_DOUBLE_EQ(c.odometry.rightWheelRadius(), 0.0321);
  EXPECT_DOUBLE_EQ(c.odometry.ekf.wheel_distance_m, 0.204);
  EXPECT_DOUBLE_EQ(c.assembler.lidar_time_offset_s, 0.003);
  EXPECT_DOUBLE_EQ(c.odometry.ekf.initial_bias_rad_s, 0.01);
  EXPECT_DOUBLE_EQ(plain.odometry.rightWheelRadius(), plain.odometry.wheel_radius_m);
  // A --set of a calibrated key still wins.
  EXPECT_DOUBLE_EQ(
      loadMobileLidarConfig(rig_b, {"calibration_file=" + (dir / "rig_calibration.yaml").string(),
                                    "lidar.time_offset_s=0.001"})
          .assembler.lidar_time_offset_s,
      0.001);
  const Scene scene(testing_scene::handScene(), PlateConfig{});
  const auto car = makeSimCar(c, scene, 1, 0), plain_car = makeSimCar(plain, scene, 1, 0);
  EXPECT_TRUE(car->trueT_BL().isApprox(plain_car->trueT_BL(), 1e-15));
  EXPECT_DOUBLE_EQ(car->trueWheelDistance(), plain_car->trueWheelDistance());
  EXPECT_DOUBLE_EQ(car->nominalWheels().radius_m, plain.odometry.wheel_radius_m);
  EXPECT_DOUBLE_EQ(car->nominalWheels().radiusOf(true, c.sim),
                   plain_car->nominalWheels().radiusOf(true, plain.sim));
  // A right wheel the rig file itself gives is the simulated car's.
  const MobileLidarConfig right =
      loadMobileLidarConfig(rig_b, {"odometry.wheel_radius_right_m=0.033"});
  EXPECT_DOUBLE_EQ(makeSimCar(right, scene, 1, 0)->nominalWheels().radiusOf(true, right.sim),
                   0.033 * (1.0 + right.sim.wheel_radius_right_error_fraction));
  // A key the rig file does not have is refused, naming the calibration file.
  f.parameters = {{"odometry.no_such_key", 1.0}};
  writeRigCalibration((dir / "rig_calibration.yaml").string(), f);
  try {
    loadMobileLidarConfig(rig_b, {"calibration_file=" + (dir / "rig_calibration.yaml").string()});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("parameters.odometry.no_such_key"), std::string::npos)
        << e.what();
  }
  std::filesystem::remove_all(dir);
}

// A value the calibration file gives that the rig's checks refuse is blamed on that file, not on
// the rig file that holds a good one; a --set of the key replaces it (and is blamed instead).
TEST(MobileLidarConfig, ARefusedCalibratedValueNamesTheCalibrationFile) {
  const std::filesystem::path dir = emptyTempDir("sweepmap_rig_b_bad_calibration");
  RigCalibrationFile f;
  f.parameters = {{"mounting.x_m", 0.1031}, {"odometry.wheel_distance_m", -0.2}};
  const std::string file = (dir / "rig_calibration.yaml").string();
  writeRigCalibration(file, f);
  const std::string rig_b = std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b.yaml";
  const auto error = [&](const std::vector<std::string>& sets) {
    try {
      loadMobileLidarConfig(rig_b, sets);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string e = error({"calibration_file=" + file});
  EXPECT_EQ(e.rfind(file + ": key 'odometry.wheel_distance_m' must be > 0", 0), 0u) << e;
  EXPECT_NE(e.find("parameters.odometry.wheel_distance_m"), std::string::npos) << e;
  EXPECT_NE(e.find("rig file " + rig_b), std::string::npos) << e;
  EXPECT_EQ(error({"calibration_file=" + file, "odometry.wheel_distance_m=0.21"}), "");
  const std::string set = error({"calibration_file=" + file, "odometry.wheel_distance_m=0"});
  EXPECT_EQ(set.rfind(rig_b + ": key 'odometry.wheel_distance_m'", 0), 0u) << set;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace sweepmap
