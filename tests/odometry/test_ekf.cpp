#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <random>

#include "odometry/ekf.hpp"

namespace sweepmap {
namespace {

// A car on a circle (radius 0.83 m, 0.2 m/s), wheels at 50 Hz with 1 % speed noise, a gyro at
// 200 Hz with white noise and a constant bias. Optionally a slip: from 5 to 5.4 s the right
// wheel reads `slip_factor` times its speed.
struct Drive {
  struct Sample {
    int64_t utime;
    bool wheels;
    double a, b;
  };
  std::vector<Sample> samples;
  std::vector<std::pair<int64_t, Pose2>> truth;  // at every wheel sample
};

Drive simulateDrive(unsigned seed, double duration_s, bool slip, double bias = 0.01,
                    double slip_factor = 1.2) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  const double wd = 0.2, v = 0.2, w = v / 0.83;
  Drive d;
  Pose2 p;
  const int64_t dt_us = 1000;
  for (int64_t t = dt_us; t <= static_cast<int64_t>(duration_s * 1e6); t += dt_us) {
    p = integrateOdometry(p, {v, w}, 1e-3);
    if (t % 5000 == 0) d.samples.push_back({t, false, w + bias + 0.005 * n(rng), 0.0});
    if (t % 20000 == 0) {
      double vl = v - 0.5 * w * wd, vr = v + 0.5 * w * wd;
      vl *= 1.0 + 0.01 * n(rng);
      vr *= 1.0 + 0.01 * n(rng);
      if (slip && t > 5000000 && t < 5400000) vr *= slip_factor;
      d.samples.push_back({t, true, vl, vr});
      d.truth.push_back({t, p});
    }
  }
  return d;
}

void feed(OdometryEkf& ekf, const Drive::Sample& s) {
  if (s.wheels) {
    ekf.addWheels(s.utime, s.a, s.b);
  } else {
    ekf.addGyro(s.utime, s.a);
  }
}

TEST(OdometryEkf, TracksTheCircleAndLearnsGyroBias) {
  const Drive d = simulateDrive(1, 30.0, false, 0.01);
  OdometryEkf ekf(EkfConfig{});
  for (const auto& s : d.samples) feed(ekf, s);
  const Pose2 truth = d.truth.back().second;
  EXPECT_NEAR(ekf.pose().x_m, truth.x_m, 0.05);
  EXPECT_NEAR(ekf.pose().y_m, truth.y_m, 0.05);
  EXPECT_NEAR(ekf.state()[OdometryEkf::kBias], 0.01, 0.002);
  EXPECT_TRUE(ekf.trusted());
  EXPECT_EQ(ekf.counters().gated_wheels, 0);
}

// Consistency: the normalised estimation error squared of the pose, averaged over runs,
// lies within its chi-square bounds (3 dof, 25 runs, 95 %: [2.32, 3.77]) at several times.
TEST(OdometryEkf, NeesWithinChiSquareBounds) {
  const int runs = 25;
  for (double at_s : {5.0, 10.0, 20.0}) {
    double sum = 0.0, sum_theta = 0.0;
    // The drive has constant speed and turn rate: the model's random-walk accelerations are
    // set small to match it (a consistency test compares a filter with its own model).
    EkfConfig c;
    c.accel_psd = 1e-6;
    c.turn_accel_psd = 1e-6;
    c.wheel_speed_sigma_min_m_s = 1e-4;  // the simulated noise is 1 % of speed, no floor
    c.bias_psd = 1e-10;                  // the simulated bias is constant
    for (int r = 0; r < runs; ++r) {
      const Drive d = simulateDrive(100 + r, at_s, false);
      OdometryEkf ekf(c);
      for (const auto& s : d.samples) feed(ekf, s);
      const Pose2 t = d.truth.back().second;
      Eigen::Vector3d e(ekf.pose().x_m - t.x_m, ekf.pose().y_m - t.y_m,
                        ekf.pose().theta_rad - t.theta_rad);
      const Eigen::Matrix3d P = ekf.covariance().topLeftCorner<3, 3>();
      sum += e.dot(P.ldlt().solve(e));
      sum_theta += e[2] * e[2] / P(2, 2);
    }
    const double nees = sum / runs;
    std::cout << "mean NEES at " << at_s << " s: " << nees << " (heading alone " << sum_theta / runs
              << ")\n";
    EXPECT_GT(nees, 2.32) << "too pessimistic at " << at_s << " s";
    EXPECT_LT(nees, 3.77) << "overconfident at " << at_s << " s";
  }
}

TEST(OdometryEkf, SlipIsRejectedByTheGate) {
  const Drive slipping = simulateDrive(7, 10.0, true);
  const Drive clean = simulateDrive(7, 10.0, false);
  OdometryEkf ekf(EkfConfig{});
  for (const auto& s : slipping.samples) feed(ekf, s);
  EXPECT_GE(ekf.counters().gated_wheels, 15);  // 0.4 s of 50 Hz wheel samples
  // Plain odometry through the slip turns too far; the EKF does not.
  Pose2 odo;
  int64_t last = 0;
  for (const auto& s : slipping.samples) {
    if (!s.wheels) continue;
    odo = integrateOdometry(odo, twistFromWheels(s.a, s.b, 0.2), 1e-6 * double(s.utime - last));
    last = s.utime;
  }
  const Pose2 truth = clean.truth.back().second;
  const double ekf_err = std::abs(ekf.pose().theta_rad - truth.theta_rad);
  const double odo_err = std::abs(odo.theta_rad - truth.theta_rad);
  std::cout << "heading error after slip: odometry " << odo_err << " rad, EKF " << ekf_err
            << " rad\n";
  EXPECT_LT(ekf_err, 0.2 * odo_err);
}

TEST(OdometryEkf, OutOfOrderInputGivesTheOrderedEstimate) {
  const Drive d = simulateDrive(3, 8.0, true);
  OdometryEkf ordered(EkfConfig{}), shuffled(EkfConfig{});
  for (const auto& s : d.samples) feed(ordered, s);
  // Deliver in blocks of 20 in reversed order: every message up to ~0.1 s late.
  auto samples = d.samples;
  for (size_t i = 0; i + 20 <= samples.size(); i += 20) {
    std::reverse(samples.begin() + i, samples.begin() + i + 20);
  }
  for (const auto& s : samples) feed(shuffled, s);
  EXPECT_GT(shuffled.counters().reordered, 100);
  EXPECT_EQ(ordered.state(), shuffled.state());
  EXPECT_EQ(ordered.covariance(), shuffled.covariance());
  EXPECT_EQ(ordered.counters().gated_wheels, shuffled.counters().gated_wheels);
}

// Wheel readings given with their interval are checked against the gyro samples within it; a
// gyro sample arriving after such a reading re-applies it: still the ordered estimate. The
// wheels' mid-times are off the gyro's 5 ms grid, and the slip is gated.
TEST(OdometryEkf, WheelIntervalsKeepTheOrderedEstimateAndGateTheSlip) {
  const Drive d = simulateDrive(3, 8.0, true);
  const auto feedTimed = [](OdometryEkf& ekf, const Drive::Sample& s) {
    if (s.wheels) {
      ekf.addWheels(s.utime - 7500, s.a, s.b, 20000);  // a 20 ms interval ending 2.5 ms early
    } else {
      ekf.addGyro(s.utime, s.a);
    }
  };
  OdometryEkf ordered(EkfConfig{}), shuffled(EkfConfig{});
  for (const auto& s : d.samples) feedTimed(ordered, s);
  auto samples = d.samples;
  for (size_t i = 0; i + 20 <= samples.size(); i += 20) {
    std::reverse(samples.begin() + i, samples.begin() + i + 20);
  }
  for (const auto& s : samples) feedTimed(shuffled, s);
  EXPECT_EQ(ordered.state(), shuffled.state());
  EXPECT_EQ(ordered.covariance(), shuffled.covariance());
  EXPECT_EQ(ordered.counters().gated_wheels, shuffled.counters().gated_wheels);
  EXPECT_EQ(ordered.counters().gated_gyro, shuffled.counters().gated_gyro);
  // 0.4 s of 50 Hz wheel samples, and up to 0.2 s after (the slip test's longer window still
  // holds the slip).
  EXPECT_GE(ordered.counters().gated_wheels, 15);
  EXPECT_LE(ordered.counters().gated_wheels, 32);
}

// A slip of 8 % at 0.2 m/s turns the wheels 0.08 rad/s faster than the gyro: under the gate of
// one 20 ms reading (0.085 rad/s), 11 sigma over 0.2 s. Caught over the window, and the wheel
// that did not slip keeps the distance.
TEST(OdometryEkf, ASlipTooSmallForOneReadingIsCaughtOverSeveral) {
  const Drive d = simulateDrive(5, 10.0, true, 0.01, 1.03);
  OdometryEkf ekf(EkfConfig{});
  for (const auto& s : d.samples) {
    if (s.wheels) {
      ekf.addWheels(s.utime - 10000, s.a, s.b, 20000);  // the mean over the last 20 ms
    } else {
      ekf.addGyro(s.utime, s.a);
    }
  }
  std::cout << "gated wheel readings: " << ekf.counters().gated_wheels << "\n";
  EXPECT_GE(ekf.counters().gated_wheels, 12);  // of the slip's 20 readings
  const Pose2 truth = d.truth.back().second;
  EXPECT_NEAR(ekf.pose().x_m, truth.x_m, 0.01);
  EXPECT_NEAR(ekf.pose().y_m, truth.y_m, 0.01);
}

TEST(OdometryEkf, BadInputRejectedAndStateStaysFinite) {
  OdometryEkf ekf(EkfConfig{});
  EXPECT_TRUE(ekf.addWheels(10000, 0.2, 0.2));
  EXPECT_FALSE(ekf.addWheels(20000, std::nan(""), 0.2));
  EXPECT_FALSE(ekf.addGyro(20000, std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(ekf.addWheels(30000, 500.0, 0.2));  // absurd speed
  EXPECT_FALSE(ekf.addGyro(30000, 1e3));           // absurd rate
  EXPECT_EQ(ekf.counters().invalid, 4);
  EXPECT_TRUE(ekf.addWheels(5000000, 0.2, 0.2));
  EXPECT_FALSE(ekf.addWheels(1000, 0.2, 0.2));  // far older than the history
  EXPECT_EQ(ekf.counters().too_old, 1);
  EXPECT_TRUE(ekf.state().allFinite());
  EXPECT_TRUE(ekf.covariance().allFinite());
}

TEST(OdometryEkf, WheelsAloneWorkButLoseTrustOverTime) {
  EkfConfig c;
  OdometryEkf ekf(c);
  for (int64_t t = 20000; t <= 600000000; t += 20000) ekf.addWheels(t, 0.19, 0.21);
  EXPECT_TRUE(ekf.state().allFinite());
  EXPECT_NEAR(ekf.state()[OdometryEkf::kW], 0.1, 1e-3);
  EXPECT_FALSE(ekf.trusted()) << "heading sigma " << std::sqrt(ekf.covariance()(2, 2));
}

TEST(OdometryEkf, ImuYawBoundsTheHeadingDriftOfABiasedNoisyGyro) {
  // 10 minutes on the circle: gyro noise and an imperfectly learned bias integrate into
  // heading drift; the IMU's own yaw (a constant offset plus white noise) bounds it.
  const Drive d = simulateDrive(11, 600.0, false, 0.02);
  EkfConfig with_yaw;
  with_yaw.yaw_sigma_rad = 0.002;
  OdometryEkf gyro_only(EkfConfig{}), fused(with_yaw);
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 0.002);
  const double offset = 0.4;  // the IMU's yaw zero is not the world's
  size_t k = 0;
  double max_err_gyro = 0, max_err_fused = 0;
  for (const auto& s : d.samples) {
    feed(gyro_only, s);
    feed(fused, s);
    if (s.wheels) {
      const Pose2& t = d.truth[k++].second;
      // An IMU reports its yaw wrapped to (-pi, pi]; the gate (p = 0.999) rejects a few.
      fused.addYaw(s.utime + 1000, std::remainder(t.theta_rad + offset + n(rng), 2 * M_PI));
      max_err_gyro =
          std::max(max_err_gyro,
                   std::abs(std::remainder(gyro_only.pose().theta_rad - t.theta_rad, 2 * M_PI)));
      max_err_fused = std::max(
          max_err_fused, std::abs(std::remainder(fused.pose().theta_rad - t.theta_rad, 2 * M_PI)));
    }
  }
  EXPECT_GT(fused.counters().yaw, 29900) << "gated " << fused.counters().gated_yaw;
  EXPECT_LT(fused.counters().gated_yaw, 100);
  EXPECT_LT(max_err_fused, 0.01) << "gyro only: " << max_err_gyro;
  EXPECT_LT(max_err_fused, max_err_gyro);
  EXPECT_FALSE(fused.addYaw(700000000, std::nan("")));
  EXPECT_EQ(fused.counters().invalid, 1);
  EXPECT_TRUE(fused.state().allFinite());
}

TEST(OdometryEkf, YawIsIgnoredWhenNotConfigured) {
  OdometryEkf ekf(EkfConfig{});
  EXPECT_TRUE(ekf.addWheels(10000, 0.2, 0.2));
  EXPECT_FALSE(ekf.addYaw(20000, 0.3));
  EXPECT_EQ(ekf.counters().yaw, 0);
  EXPECT_EQ(ekf.counters().invalid, 0);
}

}  // namespace
}  // namespace sweepmap
