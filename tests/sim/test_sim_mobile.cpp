// The simulated rig-B car (sim/mobile.hpp) on hand cases: encoder counts of a straight
// drive, wheel slip, IMU bias and noise statistics, lidar ranges to known surfaces.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "sim/mobile.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kStart = 1'000'000;

SceneConfig labScene() {
  return loadScene(std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_lab.yaml");
}

PlateConfig plate() { return PlateConfig{}; }

// Lidar 0.1 m ahead of the axle, 0.3 m above the floor, vertical (nominal rpy 0).
const Eigen::Vector3d kRpy0 = Eigen::Vector3d::Zero();
const Eigen::Vector3d kLidarPos(0.1, 0.0, 0.3);

SimMobileConfig quiet() {
  SimMobileConfig c;
  c.encoder_speed_sigma_fraction = 0.0;
  c.slip_mean_interval_s = 0.0;
  c.gyro_sigma_rad_s = 0.0;
  c.accel_sigma_m_s2 = 0.0;
  c.attitude_sigma_deg = 0.0;
  c.range_sigma_fraction = 0.0;
  c.gamma_true_rad = c.beta_true_rad = c.alpha_true_rad = 0.0;
  c.wheel_radius_left_error_fraction = c.wheel_radius_right_error_fraction = 0.0;
  c.wheel_distance_error_m = 0.0;
  c.lever_error_x_m = c.lever_error_y_m = c.lever_error_z_m = 0.0;
  c.lidar_time_offset_ms = 0.0;
  c.switchArtefactsOff();
  return c;
}

// quiet(), driving `path` for duration_s.
SimMobileConfig quietDrive(const std::string& path, double duration_s) {
  SimMobileConfig c = quiet();
  c.path = path;
  c.duration_s = duration_s;
  return c;
}

TEST(MobilePath, CircleAndRoundedRectangleAreClosedAndContinuous) {
  const MobilePath c = MobilePath::circle(-3.0, 0.0, 0.83);
  EXPECT_NEAR(c.length(), 2 * M_PI * 0.83, 1e-12);
  const Pose2 p0 = c.poseAt(0.0), p1 = c.poseAt(c.length());
  EXPECT_NEAR(p1.x_m, p0.x_m, 1e-9);
  EXPECT_NEAR(p1.y_m, p0.y_m, 1e-9);
  EXPECT_NEAR(p1.theta_rad - p0.theta_rad, 2 * M_PI, 1e-9);  // unwrapped
  const Pose2 q = c.poseAt(c.length() / 4);                  // quarter turn: rightmost point
  EXPECT_NEAR(q.x_m, -3.0 + 0.83, 1e-9);
  EXPECT_NEAR(q.y_m, 0.0, 1e-9);

  const MobilePath r = MobilePath::roundedRectangle(-4.5, 4.5, -2.0, 2.0, 0.5);
  EXPECT_NEAR(r.length(), 2 * 8.0 + 2 * 3.0 + M_PI, 1e-9);
  // Continuity: small steps move by about the step everywhere.
  Pose2 prev = r.poseAt(0.0);
  for (double s = 0.01; s <= r.length() + 1e-9; s += 0.01) {
    const Pose2 p = r.poseAt(s);
    EXPECT_NEAR(std::hypot(p.x_m - prev.x_m, p.y_m - prev.y_m), 0.01, 1e-4) << s;
    prev = p;
  }
  EXPECT_NEAR(r.poseAt(r.length()).theta_rad, 2 * M_PI, 1e-9);  // one lap: one turn
}

// calib rig's drive: straights crossing at the centre, a right-hand lobe and a left-hand one,
// closed with no net turn, continuous, the lobes at their radius about their centres.
TEST(MobilePath, FigureEightTurnsBothWaysAndCloses) {
  const double r = 0.8, spacing = 2.4, d = 1.2, phi = std::asin(r / d);
  const MobilePath f = MobilePath::figureEight(-2.5, 0.0, r, spacing);
  EXPECT_NEAR(f.length(), 4 * std::sqrt(d * d - r * r) + 2 * r * (M_PI + 2 * phi), 1e-9);
  EXPECT_TRUE(f.closed());
  EXPECT_NEAR(f.poseAt(f.length() * (1 - 1e-12)).theta_rad, phi, 1e-9);  // no net turn
  double most_right = 0, most_left = 0;
  Pose2 prev = f.poseAt(0.0);
  for (double s = 0.01; s <= f.length() + 1e-9; s += 0.01) {
    const Pose2 p = f.poseAt(s);
    EXPECT_NEAR(std::hypot(p.x_m - prev.x_m, p.y_m - prev.y_m), 0.01, 1e-4) << s;
    most_right = std::min(most_right, f.curvatureAt(s));
    most_left = std::max(most_left, f.curvatureAt(s));
    // On a lobe: at its radius from its centre.
    if (f.curvatureAt(s) != 0.0) {
      const double cx = f.curvatureAt(s) < 0 ? -2.5 + d : -2.5 - d;
      EXPECT_NEAR(std::hypot(p.x_m - cx, p.y_m), r, 1e-9) << s;
    }
    prev = p;
  }
  EXPECT_NEAR(most_right, -1 / r, 1e-12);
  EXPECT_NEAR(most_left, 1 / r, 1e-12);
  EXPECT_NEAR(f.poseAt(0).x_m, -2.5, 1e-12);
}

// Stops: the car rests for stop_duration_s after each leg, the distance holds still, and
// the accelerometer's along-track reading follows the ramps of every leg.
TEST(SimMobile, StopsAfterEachLegOfDriving) {
  const Scene scene(labScene(), plate());
  SimMobileConfig c = quietDrive("figure8", 25.0);
  c.stop_interval_s = 10.0;
  c.stop_duration_s = 2.0;
  SimMobile car(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 1, kStart);
  const double leg = 0.2 * (10.0 - 0.4);  // ramps of 0.4 s at 0.5 m/s^2
  EXPECT_NEAR(car.distanceAt(10.0), leg, 1e-9);
  EXPECT_NEAR(car.distanceAt(11.5), leg, 1e-9);
  EXPECT_EQ(car.speedAt(11.0), 0.0);
  EXPECT_EQ(car.turnRateAt(11.0), 0.0);
  EXPECT_NEAR(car.speedAt(12.2), 0.1, 1e-9);  // ramping up again
  EXPECT_NEAR(car.accelerationAt(12.2), 0.5, 1e-12);
  EXPECT_NEAR(car.accelerationAt(21.9), -0.5, 1e-12);
  EXPECT_NEAR(car.distanceAt(22.0), 2 * leg, 1e-9);
  // The last leg is cut by the end of the run, and ramps down to stop at it.
  EXPECT_NEAR(car.distanceAt(25.0), 2 * leg + 0.2 * (1.0 - 0.4), 1e-9);
  EXPECT_EQ(car.speedAt(25.0), 0.0);
  const auto ticks = car.wheelTicks();
  // At rest, the encoders do not count.
  const auto at = [&](double t) { return ticks[size_t(std::lround(t * 50))]; };
  EXPECT_EQ(at(10.5).left, at(11.5).left);
  EXPECT_EQ(at(10.5).right, at(11.5).right);
}

TEST(SimMobile, StraightDriveTicksAreDistanceOverCircumference) {
  const Scene scene(labScene(), plate());
  SimMobileConfig c = quietDrive("loop", 15.0);  // starts in the middle of a 8 m straight
  WheelGeometry w;
  SimMobile car(c, w, kRpy0, kLidarPos, scene, 1, kStart);
  const auto ticks = car.wheelTicks();
  ASSERT_EQ(ticks.size(), 751u);  // 50 Hz, both ends
  EXPECT_EQ(ticks.front().utime, kStart);
  EXPECT_EQ(ticks.back().utime, kStart + 15'000'000);
  const double d = car.distanceAt(15.0);
  EXPECT_NEAR(d, 0.2 * (15.0 - 0.4), 1e-9);  // ramps of 0.4 s at 0.5 m/s^2
  const double expected = d / (2 * M_PI * w.radius_m) * w.ticks_per_revolution;
  EXPECT_NEAR(double(ticks.back().left), expected, 1.0);
  EXPECT_NEAR(double(ticks.back().right), expected, 1.0);
  for (const auto& t : ticks) {
    const double e = car.distanceAt(1e-6 * double(t.utime - kStart)) / (2 * M_PI * w.radius_m) *
                     w.ticks_per_revolution;
    EXPECT_NEAR(double(t.left), e, 1.0);
    EXPECT_EQ(t.left, t.right);
  }
  // Truth: straight along W's x.
  const Pose2 end = car.worldPoseAt(15.0);
  EXPECT_NEAR(end.x_m, d, 1e-9);
  EXPECT_NEAR(end.y_m, 0.0, 1e-9);
  EXPECT_NEAR(end.theta_rad, 0.0, 1e-12);
}

// A real build's errors: each wheel counts its ground distance over its own true radius, the
// lidar sits at the true lever arm, and its stamps run ahead by the clock offset.
TEST(SimMobile, BuildErrorsBiasTicksLeverAndStamps) {
  const Scene scene(labScene(), plate());
  SimMobileConfig c = quietDrive("loop", 15.0);
  c.wheel_radius_left_error_fraction = 0.01;
  c.wheel_radius_right_error_fraction = -0.012;
  c.lever_error_y_m = -0.002;
  c.lidar_time_offset_ms = 3.0;
  WheelGeometry w;
  SimMobile car(c, w, kRpy0, kLidarPos, scene, 1, kStart);
  const auto ticks = car.wheelTicks();
  const double d = car.distanceAt(15.0);  // straight: both wheels roll d
  EXPECT_NEAR(double(ticks.back().left),
              d / (2 * M_PI * w.radius_m * 1.01) * w.ticks_per_revolution, 1.0);
  EXPECT_NEAR(double(ticks.back().right),
              d / (2 * M_PI * w.radius_m * 0.988) * w.ticks_per_revolution, 1.0);
  EXPECT_NEAR(car.trueT_BL().translation().y(), -0.002, 1e-15);
  const auto scans = car.scans();
  ASSERT_FALSE(scans.empty());
  EXPECT_EQ(scans.front().utime, kStart + 3000);
}

TEST(SimMobile, SlipMakesOneWheelRunFastOnlyDuringTheEvent) {
  const Scene scene(labScene(), plate());
  SimMobileConfig c = quietDrive("loop", 18.0);
  c.slip_mean_interval_s = 3.0;
  WheelGeometry w;
  SimMobile car(c, w, kRpy0, kLidarPos, scene, 7, kStart);
  ASSERT_GE(car.slips().size(), 2u);
  const auto ticks = car.wheelTicks();
  int inside = 0, outside = 0;
  for (size_t k = 1; k < ticks.size(); ++k) {
    const double t0 = 1e-6 * double(ticks[k - 1].utime - kStart);
    const double t1 = 1e-6 * double(ticks[k].utime - kStart);
    const int64_t dl = ticks[k].left - ticks[k - 1].left, dr = ticks[k].right - ticks[k - 1].right;
    const SlipEvent* in = nullptr;
    bool touches = false;
    for (const auto& e : car.slips()) {
      if (t1 > e.start_s && t0 < e.end_s) touches = true;
      if (t0 >= e.start_s && t1 <= e.end_s) in = &e;
    }
    if (!touches) {
      EXPECT_LE(std::abs(dl - dr), 1) << "at " << t0 << " s";
      ++outside;
    } else if (in && t0 > 0.5 && t1 < c.duration_s - 0.5) {
      const int64_t fast = in->right ? dr : dl, slow = in->right ? dl : dr;
      EXPECT_NEAR(double(fast - slow), in->fraction * double(slow), 2.0) << "at " << t0 << " s";
      EXPECT_GT(fast, slow);
      ++inside;
    }
  }
  EXPECT_GT(inside, 5);
  EXPECT_GT(outside, 500);
  for (const auto& e : car.slips()) {
    EXPECT_GE(e.end_s - e.start_s, 0.2 - 1e-12);
    EXPECT_LE(e.end_s - e.start_s, 0.5 + 1e-12);
    EXPECT_GE(e.fraction, 0.1);
    EXPECT_LE(e.fraction, 0.3);
  }
  // Slip does not move the car: the truth is still a straight line.
  EXPECT_NEAR(car.worldPoseAt(18.0).y_m, 0.0, 1e-9);
}

TEST(SimMobile, ImuBiasAndNoiseStatistics) {
  const Scene scene(labScene(), plate());
  SimMobileConfig c;  // defaults: gyro 0.005 rad/s noise, 0.01 rad/s z bias
  c.duration_s = 60.0;
  SimMobile car(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 3, kStart);
  const auto imu = car.imu();
  ASSERT_EQ(imu.size(), 12001u);
  std::vector<double> ez, ex, roll, pitch, yaw;
  for (const auto& m : imu) {
    const double t = 1e-6 * double(m.utime - kStart);
    ez.push_back(m.gyro[2] - car.turnRateAt(t));
    ex.push_back(m.gyro[0]);
    roll.push_back(m.rpy[0]);
    pitch.push_back(m.rpy[1]);
    yaw.push_back(std::remainder(m.rpy[2] - car.worldPoseAt(t).theta_rad, 2 * M_PI));
  }
  const auto mean = [](const std::vector<double>& v) {
    return std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
  };
  const auto sd = [&](const std::vector<double>& v) {
    const double m = mean(v);
    double s = 0;
    for (double x : v) s += (x - m) * (x - m);
    return std::sqrt(s / double(v.size() - 1));
  };
  const double n = double(imu.size());
  EXPECT_NEAR(mean(ez), 0.01, 4 * 0.005 / std::sqrt(n));
  EXPECT_NEAR(sd(ez), 0.005, 0.005 * 0.05);
  EXPECT_NEAR(mean(ex), 0.0, 4 * 0.005 / std::sqrt(n));
  EXPECT_NEAR(sd(ex), 0.005, 0.005 * 0.05);
  const double deg = M_PI / 180;
  EXPECT_NEAR(mean(roll), 0.3 * deg, 0.01 * deg);
  EXPECT_NEAR(mean(pitch), -0.2 * deg, 0.01 * deg);
  EXPECT_NEAR(mean(yaw), 0.5 * deg, 0.01 * deg);
  EXPECT_NEAR(sd(roll), 0.05 * deg, 0.005 * deg);
  // Circle at 0.2 m/s, radius 0.83 m: turn rate 0.241 rad/s while cruising.
  EXPECT_NEAR(car.turnRateAt(30.0), 0.2 / 0.83, 1e-12);
}

TEST(SimMobile, LidarSeesKnownSurfacesAtTheirAnalyticRange) {
  const Scene scene(labScene(), plate());
  SimMobileConfig c = quiet();
  c.speed_m_s = 1e-9;  // standing at the circle's start: (-3, -0.83), facing +x
  const auto check = [&](double gamma, double expected_up) {
    c.gamma_true_rad = gamma;
    SimMobile car(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 1, kStart);
    ASSERT_EQ(car.raysPerScan(), 714);
    std::mt19937_64 rng(1);
    const Scan2D s = car.makeScan(0, &rng);
    ASSERT_EQ(s.ranges_m.size(), 714u);
    EXPECT_EQ(s.time_increment_ns, 200'000);
    EXPECT_EQ(s.utime, kStart);
    // Ray 357 points up (angle 0): the ceiling at 2.5 m, lidar at 0.3 m.
    EXPECT_NEAR(s.rayAngle(357), 0.0, 1e-12);
    EXPECT_NEAR(s.ranges_m[357], expected_up, 1e-5);
    if (gamma != 0.0) return;
    // Ray 0 points down (angle -pi): the floor 0.3 m below.
    EXPECT_NEAR(s.ranges_m[0], 0.3, 1e-5);
    // Rays near -90 deg look right (-y): the -Y wall, 2.5 - 0.83 = 1.67 m away sideways.
    for (size_t i : {178u, 179u, 200u}) {
      const double a = s.rayAngle(i);
      EXPECT_NEAR(s.ranges_m[i], 1.67 / std::abs(std::sin(a)), 1e-5) << i;
    }
    // Rays near +90 deg look left (+y): the +Y wall, 3.33 m away.
    for (size_t i : {535u, 536u}) {
      const double a = s.rayAngle(i);
      EXPECT_NEAR(s.ranges_m[i], 3.33 / std::abs(std::sin(a)), 1e-5) << i;
    }
  };
  check(0.0, 2.2);
  // Mounting error about body x tilts the scan plane sideways: the up ray meets the ceiling
  // at 2.2 / cos(gamma).
  check(0.1, 2.2 / std::cos(0.1));
}

TEST(SimMobile, RangeNoiseIsOnePercentAndSeedDeterministic) {
  const Scene scene(labScene(), plate());
  SimMobileConfig c = quiet();
  c.speed_m_s = 1e-9;
  c.range_sigma_fraction = 0.01;
  c.duration_s = 30.0;
  SimMobile car(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 5, kStart);
  const auto scans = car.scans();
  EXPECT_EQ(scans.size(), 210u);  // 7 Hz for 30 s
  std::vector<double> rel;
  for (const auto& s : scans) rel.push_back(s.ranges_m[357] / 2.2 - 1.0);
  double m = 0, v = 0;
  for (double x : rel) m += x / double(rel.size());
  for (double x : rel) v += (x - m) * (x - m) / double(rel.size() - 1);
  EXPECT_NEAR(std::sqrt(v), 0.01, 0.0015);
  SimMobile again(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 5, kStart);
  const auto scans2 = again.scans();
  ASSERT_EQ(scans2.size(), scans.size());
  EXPECT_EQ(scans2[17].ranges_m, scans[17].ranges_m);
  SimMobile other(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 6, kStart);
  EXPECT_NE(other.scans()[17].ranges_m, scans[17].ranges_m);
}

// The scene's artefacts on the car's lidar, each alone against the same noise-free scans
// without them: the window in the -Y wall returns nothing, people only ever come in front of
// the room, a mixed pixel lies between its own surface and its neighbour's, and a scan made
// alone (as the emulator makes them) is the run's.
TEST(SimMobile, SceneArtefactsEachDoWhatTheySay) {
  const Scene scene(labScene(), plate());
  SimMobileConfig off = quiet();
  off.speed_m_s = 1e-9;          // standing at (-1, -0.83), facing +x: the scan plane at x = -1
  off.circle_center_x_m = -1.0;  // crosses the window (x -1.75..-0.25, z 0.9..2.1)
  off.duration_s = 20.0;
  const auto scansOf = [&](const SimMobileConfig& c) {
    return SimMobile(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 3, kStart).scans();
  };
  const std::vector<Scan2D> plain = scansOf(off);
  ASSERT_EQ(plain.size(), 140u);

  SimMobileConfig window = off;
  window.window_width_m = 1.5;
  const Scan2D w = scansOf(window)[0];
  int in_window = 0;
  for (size_t i = 0; i < w.ranges_m.size(); ++i) {
    const double r = plain[0].ranges_m[i], a = plain[0].rayAngle(i);
    const double y = -0.83 + r * std::sin(a), z = 0.3 + r * std::cos(a);
    const bool glass = std::abs(y + 2.5) < 1e-4 && z > 0.9 && z < 2.1;
    in_window += glass;
    EXPECT_EQ(w.ranges_m[i], glass ? 0.0f : plain[0].ranges_m[i]) << i;
  }
  EXPECT_GT(in_window, 20);

  SimMobileConfig people = off;
  people.people = 2;
  const std::vector<Scan2D> walked = scansOf(people);
  int nearer = 0;
  for (size_t k = 0; k < plain.size(); ++k) {
    for (size_t i = 0; i < plain[k].ranges_m.size(); ++i) {
      ASSERT_LE(walked[k].ranges_m[i], plain[k].ranges_m[i]) << k << " " << i;
      ASSERT_GT(walked[k].ranges_m[i], 0.0f) << k << " " << i;
      nearer += walked[k].ranges_m[i] < plain[k].ranges_m[i];
    }
  }
  EXPECT_GT(nearer, 100);  // two people crossing the scan plane at 1 m/s

  SimMobileConfig mixed = off;
  mixed.mixed_pixel_probability = 0.5;
  const Scan2D m = scansOf(mixed)[0];
  const std::vector<float>& r = plain[0].ranges_m;
  int mixed_rays = 0;
  for (size_t i = 1; i + 1 < r.size(); ++i) {
    if (m.ranges_m[i] == r[i]) continue;
    ++mixed_rays;
    const auto between = [&](size_t j) {
      return std::abs(r[j] - r[i]) > 0.05f && m.ranges_m[i] >= std::min(r[i], r[j]) &&
             m.ranges_m[i] <= std::max(r[i], r[j]);
    };
    EXPECT_TRUE(between(i - 1) || between(i + 1)) << i;
  }
  EXPECT_GT(mixed_rays, 2);

  SimMobileConfig all = off;  // every artefact at its default, no noise
  const SimMobileConfig defaults;
  static_cast<SceneArtefactConfig&>(all) = defaults;
  const std::vector<Scan2D> run = scansOf(all);
  SimMobile car(all, WheelGeometry{}, kRpy0, kLidarPos, scene, 3, kStart);
  std::mt19937_64 rng(99);
  for (int64_t k : {0, 5, 77}) EXPECT_EQ(car.makeScan(k, &rng).ranges_m, run[size_t(k)].ranges_m);
}

TEST(SimMobile, RejectsBadConfiguration) {
  const Scene scene(labScene(), plate());
  SimMobileConfig c;
  c.path = "figure9";
  EXPECT_THROW(SimMobile(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 1, kStart), ConfigError);
  c.path = "figure8";
  c.figure8_lobe_spacing_m = 1.5;  // lobes of 0.8 m overlap
  EXPECT_THROW(SimMobile(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 1, kStart), ConfigError);
  c.figure8_lobe_spacing_m = 2.4;
  c.figure8_center_x_m = -3.5;  // the -X lobe through the wall
  EXPECT_THROW(SimMobile(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 1, kStart), ConfigError);
  c = SimMobileConfig{};
  c.circle_center_x_m = 4.5;  // circle through the wall
  EXPECT_THROW(SimMobile(c, WheelGeometry{}, kRpy0, kLidarPos, scene, 1, kStart), ConfigError);
}

}  // namespace
}  // namespace sweepmap
