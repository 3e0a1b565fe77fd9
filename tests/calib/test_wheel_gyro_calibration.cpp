// Rig B's wheels against its gyro (calib/wheel_gyro_calibration.hpp) on the simulated car's
// own encoder and gyro readings, with a real build's wheel errors, slip and a gyro bias: the
// figure-eight with stops determines each radius over the track and the bias within 3 sigma,
// the radii's ratio within 0.1 %; a circle at constant speed cannot separate them.
#include <gtest/gtest.h>

#include <cmath>

#include "calib/wheel_gyro_calibration.hpp"
#include "sim/mobile.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kStart = 1'000'000;

struct Drive {
  std::vector<WheelReading> wheels;
  std::vector<GyroReading> gyro;
  double k_left, k_right, bias;  // truth
};

Drive simulate(const std::string& path, double stop_interval_s, uint64_t seed,
               bool noiseless = false) {
  const Scene scene(loadScene(std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_lab.yaml"),
                    PlateConfig{});
  SimMobileConfig c;  // every build error and slip at its default
  if (noiseless) {    // the build's errors and the gyro's bias kept
    c.gyro_sigma_rad_s = c.encoder_speed_sigma_fraction = c.slip_mean_interval_s = 0.0;
  }
  c.path = path;
  c.duration_s = 120.0;
  c.stop_interval_s = stop_interval_s;
  const WheelGeometry w;
  SimMobile car(c, w, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.1, 0, 0.3), scene, seed, kStart);
  Drive d;
  for (const WheelTicks& t : car.wheelTicks()) d.wheels.push_back({t.utime, t.left, t.right});
  for (const ImuSample& m : car.imu()) d.gyro.push_back({m.utime, m.gyro[2]});
  d.k_left = w.radiusOf(false, c) / car.trueWheelDistance();
  d.k_right = w.radiusOf(true, c) / car.trueWheelDistance();
  d.bias = c.gyro_bias_z_rad_s;
  return d;
}

TEST(WheelGyroCalibration, FigureEightWithStopsDeterminesBothWheelsAndTheBias) {
  for (uint64_t seed : {1, 2, 3}) {
    const Drive d = simulate("figure8", 20.0, seed);
    const WheelGyroResult r = calibrateWheelsAgainstGyro(d.wheels, d.gyro, WheelGyroOptions{});
    ASSERT_TRUE(r.ok) << r.reason;
    const double truth[3] = {d.k_left, d.k_right, d.bias};
    for (int k = 0; k < 3; ++k) {
      const double sigma = std::sqrt(r.covariance(k, k));
      EXPECT_NEAR(r.x(k), truth[k], 3 * sigma) << "seed " << seed << " entry " << k;
    }
    // The radii's ratio (what the straights fix, the wheels' part of the radii's 0.1 %).
    const Eigen::Vector2d g(-r.x(1) / (r.x(0) * r.x(0)), 1.0 / r.x(0));
    const double ratio = r.x(1) / r.x(0),
                 ratio_sigma = std::sqrt(g.dot(r.covariance.topLeftCorner<2, 2>() * g));
    EXPECT_NEAR(ratio, d.k_right / d.k_left, 3 * ratio_sigma) << "seed " << seed;
    EXPECT_LT(std::abs(ratio / (d.k_right / d.k_left) - 1), 1e-3) << "seed " << seed;
    EXPECT_LT(ratio_sigma / ratio, 4e-4) << "seed " << seed;
    // The stops: the bias to a few percent of itself.
    EXPECT_LT(std::sqrt(r.covariance(2, 2)), 0.1 * d.bias) << "seed " << seed;
    EXPECT_GT(r.rest_rows, 20);
    EXPECT_GT(r.trimmed, 0);  // the slips
  }
}

// Noiseless readings (no gyro noise, no encoder noise but the ticks' own steps, no slip): the
// windows at rest then fit the bias to rounding, and their group's scatter with it. Before, its
// weight (1 / scatter^2) swamped the normal matrix's trace, the singularity test failed, and
// the wheels were reported undetermined. The easiest drive must calibrate.
TEST(WheelGyroCalibration, NoiselessReadingsDetermineBothWheelsAndTheBias) {
  const Drive d = simulate("figure8", 20.0, 1, /*noiseless=*/true);
  const WheelGyroResult r = calibrateWheelsAgainstGyro(d.wheels, d.gyro, WheelGyroOptions{});
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_LT(std::abs(r.x(0) / d.k_left - 1), 1e-3);
  EXPECT_LT(std::abs(r.x(1) / d.k_right - 1), 1e-3);
  EXPECT_NEAR(r.x(2), d.bias, 1e-4);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(std::isfinite(r.covariance(k, k))) << k;
}

// A circle at constant speed turns one way at one rate: both wheels always in the same
// ratio, so k_L, k_R and the bias trade off (only the ramps at the ends differ). Least squares
// still returns an answer, both k shrunk towards 0 by the encoders' noise in the rows, with a
// small absolute sigma (on a 120 s circle: k 99.6 % low at 0.4 % of the nominal k): relative to
// k, that sigma is large, and the result is not ok.
TEST(WheelGyroCalibration, CircleDoesNotSeparateTheWheels) {
  const Drive d = simulate("circle", 0.0, 1);
  const WheelGyroResult r = calibrateWheelsAgainstGyro(d.wheels, d.gyro, WheelGyroOptions{});
  EXPECT_FALSE(r.ok) << r.x.transpose() << " sigma "
                     << r.covariance.diagonal().cwiseSqrt().transpose();
  EXPECT_NE(r.reason.find("relative"), std::string::npos) << r.reason;
}

// Bad input never crashes: no readings, one reading, a gyro that stops early.
TEST(WheelGyroCalibration, TooLittleDataIsAReasonNotACrash) {
  EXPECT_FALSE(calibrateWheelsAgainstGyro({}, {}, WheelGyroOptions{}).ok);
  EXPECT_FALSE(calibrateWheelsAgainstGyro({{0, 0, 0}}, {{0, 0.0}}, WheelGyroOptions{}).ok);
  const WheelGyroResult r =
      calibrateWheelsAgainstGyro({{0, 0, 0}, {100000, 10, 10}, {200000, 20, 20}},
                                 {{0, 0.0}, {50000, 0.0}}, WheelGyroOptions{});
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.reason.empty());
}

}  // namespace
}  // namespace sweepmap
