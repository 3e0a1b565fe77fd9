#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>

#include "core/angles.hpp"
#include "hand_scene.hpp"
#include "sim/lidar.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kFirstScanUtime = 1'000'000;

// Index of the ray at `theta_deg` with the default UST-10LX layout (-135 deg, 0.25 deg).
size_t ray(double theta_deg) { return size_t(std::lround((theta_deg + 135.0) / 0.25)); }

// Hand scene (rig at (1.2, 0.8, 1.0), walls at x = +-4, y = +-3, ceiling 3 m), noise-free
// lidar of the paper's model (no tilt, mirror offset, plate thickness or scene artefacts)
// unless a test turns them on.
class SimLidarTest : public ::testing::Test {
 protected:
  SimLidarTest() {
    sim_.range_noise_sigma_mm = 0.0;
    sim_.applyPaperSettings();
  }

  void build(const SceneConfig& scene_config = testing_scene::handScene()) {
    scene_ = std::make_unique<Scene>(scene_config, plate_);
  }
  std::unique_ptr<SimLidar> lidar(uint64_t seed = 1) const {
    return std::make_unique<SimLidar>(lidar_, sim_, plate_, *scene_, &truth_, seed,
                                      kFirstScanUtime);
  }
  // First scan delivered, with the shaft standing at `phi_rad` throughout.
  Scan2D standingScan(double phi_rad) {
    truth_ = ShaftTrajectory();
    truth_.apply({0, phi_rad, 0.0, 0.0});
    auto scans = lidar()->poll(kFirstScanUtime + 100'000);
    EXPECT_FALSE(scans.empty());
    return scans.empty() ? Scan2D() : scans.front();
  }
  // Ray i in frame O from the true shaft angle (Eq. 4-6).
  Eigen::Vector3d pointInO(const Scan2D& scan, size_t i) const {
    const double r = scan.ranges_m[i], theta = scan.rayAngle(i);
    const Eigen::Vector3d p_l(sim_.lidar_offset_x_mm / 1000.0, r * std::sin(theta),
                              r * std::cos(theta));
    return Eigen::AngleAxisd(truth_.angleAt(scan.rayUtime(i)), Eigen::Vector3d::UnitZ()) * p_l;
  }

  LidarConfig lidar_;
  SimRigConfig sim_;
  PlateConfig plate_;
  ShaftTrajectory truth_;
  std::unique_ptr<Scene> scene_;
};

TEST_F(SimLidarTest, ScanLayout) {
  build();
  const Scan2D scan = standingScan(0.0);
  EXPECT_EQ(scan.utime, kFirstScanUtime);
  EXPECT_EQ(scan.seq, 0);
  EXPECT_EQ(scan.ranges_m.size(), 1081u);
  EXPECT_DOUBLE_EQ(scan.angle_min_rad, -135.0 * kDegToRad);
  EXPECT_DOUBLE_EQ(scan.angle_increment_rad, 0.25 * kDegToRad);
  EXPECT_EQ(scan.time_increment_ns, 17361);  // 1 / (40 Hz * 1440)
  EXPECT_DOUBLE_EQ(scan.range_min_m, 0.06);
  EXPECT_DOUBLE_EQ(scan.range_max_m, 10.0);
}

TEST_F(SimLidarTest, SeesWallsAtTheAnalyticRange) {
  build();
  // Shaft at 0: scan plane x = 1.2 + offset, rays from (.., 0.8, 1.0) toward +-Y and Z.
  Scan2D scan = standingScan(0.0);
  EXPECT_NEAR(scan.ranges_m[ray(90)], 2.2, 1e-6);                   // +Y wall
  EXPECT_NEAR(scan.ranges_m[ray(-90)], 3.8, 1e-6);                  // -Y wall
  EXPECT_NEAR(scan.ranges_m[ray(0)], 2.0, 1e-6);                    // ceiling
  EXPECT_NEAR(scan.ranges_m[ray(45)], 2.0 * std::sqrt(2.0), 1e-6);  // ceiling, oblique
  EXPECT_NEAR(scan.ranges_m[ray(135)], std::sqrt(2.0), 1e-6);       // floor, oblique
  // Shaft at 90 deg: ray +90 looks along -X from y = 0.8 + offset.
  scan = standingScan(90.0 * kDegToRad);
  EXPECT_NEAR(scan.ranges_m[ray(90)], 5.2, 1e-6);
  EXPECT_NEAR(scan.ranges_m[ray(-90)], 2.8, 1e-6);
  // The rig's yaw turns frame O in the room: yaw 90, shaft 0 is the same as shaft 90.
  SceneConfig turned = testing_scene::handScene();
  turned.rig_yaw_deg = 90.0;
  build(turned);
  scan = standingScan(0.0);
  EXPECT_NEAR(scan.ranges_m[ray(90)], 5.2, 1e-6);
  EXPECT_NEAR(scan.ranges_m[ray(-90)], 2.8, 1e-6);
}

// Intensity (sim/reflectance.hpp): 20000 rho |cos incidence| / (1 + r), worked out by hand for
// the rays of SeesWallsAtTheAnalyticRange: walls rho 0.7, ceiling 0.8, floor 0.3.
TEST_F(SimLidarTest, IntensityFallsWithRangeIncidenceAndReflectivity) {
  build();
  const Scan2D scan = standingScan(0.0);
  ASSERT_EQ(scan.intensities.size(), scan.ranges_m.size());
  const double c45 = std::sqrt(0.5);
  EXPECT_NEAR(scan.intensities[ray(90)], 20000 * 0.7 / 3.2, 0.5);   // +Y wall, 2.2 m, normal
  EXPECT_NEAR(scan.intensities[ray(-90)], 20000 * 0.7 / 4.8, 0.5);  // -Y wall, 3.8 m
  EXPECT_NEAR(scan.intensities[ray(0)], 20000 * 0.8 / 3.0, 0.5);    // ceiling, 2 m
  EXPECT_NEAR(scan.intensities[ray(45)], 20000 * 0.8 * c45 / (1 + 2 * std::sqrt(2.0)), 0.5);
  EXPECT_NEAR(scan.intensities[ray(135)], 20000 * 0.3 * c45 / (1 + std::sqrt(2.0)), 0.5);
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    EXPECT_EQ(scan.intensities[i] > 0.0f, scan.ranges_m[i] > 0.0f) << "ray " << i;
  }
}

TEST_F(SimLidarTest, OutOfRangeReadsZero) {
  lidar_.range_max_m = 2.5;
  build();
  const Scan2D scan = standingScan(0.0);
  EXPECT_NEAR(scan.ranges_m[ray(90)], 2.2, 1e-6);
  EXPECT_EQ(scan.ranges_m[ray(-90)], 0.0f);
  EXPECT_EQ(scan.intensities[ray(-90)], 0.0f);  // no return, no intensity
}

TEST_F(SimLidarTest, SeesThePlateWhenTheShaftTurnsOverIt) {
  build();
  // phi relative to alpha - 90 deg (where the scan plane's +Y half points along the
  // plate's middle line) turns from -70 to +70 deg at 40 deg/s.
  const double alpha = sim_.alpha_true_deg * kDegToRad;
  const double phi_mid = alpha - 90.0 * kDegToRad;
  truth_.apply({kFirstScanUtime, phi_mid - 70.0 * kDegToRad, 40.0 * kDegToRad, 0.0});
  const auto scans = lidar()->poll(kFirstScanUtime + 3'600'000);
  ASSERT_GT(scans.size(), 130u);

  const auto corners = SimLidar::plateVertices(plate_, alpha);
  const double plate_z = plate_.height_mm / 1000.0;
  int plate_points = 0;
  double min_phi = 1e9, max_phi = -1e9;
  for (const Scan2D& scan : scans) {
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      if (scan.ranges_m[i] == 0.0f) continue;
      const Eigen::Vector3d p = pointInO(scan, i);
      if (std::abs(p.z() - plate_z) > 1e-6) continue;
      ++plate_points;
      // Inside the triangle: on the same side of each edge as the opposite corner.
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d a = corners[k], b = corners[(k + 1) % 3], c = corners[(k + 2) % 3];
        EXPECT_GE((b - a).cross(p - a).z() * (b - a).cross(c - a).z(), -1e-12);
      }
      const double phi = truth_.angleAt(scan.rayUtime(i)) - phi_mid;
      min_phi = std::min(min_phi, phi);
      max_phi = std::max(max_phi, phi);
    }
  }
  EXPECT_GT(plate_points, 1000);
  // The scan plane (offset from the axis) first and last touches the hypotenuse's ends:
  // a point at azimuth psi and radius rho is in it when psi - phi = acos(offset / rho).
  const double offset = sim_.lidar_offset_x_mm / 1000.0;
  const auto touch = [&](const Eigen::Vector3d& v) {
    return std::atan2(v.y(), v.x()) - std::acos(offset / v.head<2>().norm()) - phi_mid;
  };
  EXPECT_NEAR(min_phi, touch(corners[1]), 2.0 * kDegToRad);  // about -35 deg
  EXPECT_NEAR(max_phi, touch(corners[0]), 2.0 * kDegToRad);  // about +56 deg
}

TEST_F(SimLidarTest, PlateVerticesFormTheInstalledTriangle) {
  const auto v = SimLidar::plateVertices(plate_, 30.0 * kDegToRad);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_NEAR((v[0] - v[1]).norm(), 0.112, 1e-12);                       // hypotenuse
  EXPECT_NEAR((v[2] - v[0]).dot(v[2] - v[1]), 0.0, 1e-12);               // right angle at apex
  EXPECT_NEAR((0.5 * (v[0] + v[1])).head<2>().norm(), 0.05475, 1e-12);   // base distance
  EXPECT_NEAR(std::atan2(v[2].y(), v[2].x()), 30.0 * kDegToRad, 1e-12);  // middle line
  for (const auto& p : v) EXPECT_DOUBLE_EQ(p.z(), -0.045);
}

TEST_F(SimLidarTest, SameSeedSameScansDifferentSeedDifferentNoise) {
  sim_.range_noise_sigma_mm = 12.0;
  build();
  truth_.apply({0, 0.0, 0.2, 0.0});
  const auto a = lidar(5)->poll(kFirstScanUtime + 500'000);
  const auto b = lidar(5)->poll(kFirstScanUtime + 500'000);
  const auto c = lidar(6)->poll(kFirstScanUtime + 500'000);
  sim_.range_noise_sigma_mm = 0.0;
  const auto exact = lidar(5)->poll(kFirstScanUtime + 500'000);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), c.size());
  ASSERT_GE(a.size(), 10u);
  size_t differing = 0, n = 0;
  double sum_sq = 0.0;
  for (size_t s = 0; s < a.size(); ++s) {
    EXPECT_EQ(a[s].ranges_m, b[s].ranges_m);
    EXPECT_EQ(a[s].intensities, b[s].intensities);
    for (size_t i = 0; i < a[s].ranges_m.size(); ++i) {
      if (a[s].ranges_m[i] != c[s].ranges_m[i]) ++differing;
      if (a[s].ranges_m[i] != 0.0f && exact[s].ranges_m[i] != 0.0f) {
        const double e = a[s].ranges_m[i] - exact[s].ranges_m[i];
        sum_sq += e * e;
        ++n;
      }
    }
  }
  EXPECT_GT(differing, a.size() * 1000);
  ASSERT_GT(n, 5000u);
  EXPECT_NEAR(std::sqrt(sum_sq / n), 0.012, 0.001);
}

TEST_F(SimLidarTest, SkipsScansBeforeTheTruthAndDeliversAfterLatency) {
  build();
  truth_.apply({1'100'000, 0.0, 0.0, 0.0});  // covers scan 4 (at 1.1 s) onward
  auto sim_lidar = lidar();
  // Scan 4 ends at +18749 us (1080 rays of 17361 ns) and arrives 50 ms later.
  const int64_t delivered = 1'100'000 + 18'749 + 50'000;
  EXPECT_TRUE(sim_lidar->poll(delivered - 1).empty());
  EXPECT_EQ(sim_lidar->skippedScans(), 4);
  auto scans = sim_lidar->poll(delivered);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].seq, 4);
  EXPECT_EQ(scans[0].utime, 1'100'000);
  scans = sim_lidar->poll(delivered + 1'000'000);
  ASSERT_EQ(scans.size(), 40u);
  for (size_t k = 0; k < scans.size(); ++k) {
    EXPECT_EQ(scans[k].seq, int64_t(5 + k));
    EXPECT_EQ(scans[k].utime, kFirstScanUtime + (5 + int64_t(k)) * 25'000);
  }
  EXPECT_EQ(sim_lidar->skippedScans(), 4);
}

// Two simulated seconds of scans (43k rays per second), every one at the scan rate; prints the
// simulator's speed (a figure, not asserted: `make bench` measures speed).
TEST_F(SimLidarTest, TwoSimulatedSecondsOfScans) {
  sim_.range_noise_sigma_mm = 12.0;
  build(loadScene(std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_conference_room.yaml"));
  truth_.apply({0, 0.0, M_PI / 16, 0.0});  // mode 7: 180 deg in 16 s
  auto sim_lidar = lidar();
  const auto start = std::chrono::steady_clock::now();
  const auto scans = sim_lidar->poll(kFirstScanUtime + 2'000'000);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double rays = double(scans.size()) * lidar_.beam_count;
  const double simulated_s = double(scans.size()) / lidar_.scan_rate_hz;
  std::cout << "[ sim lidar] " << rays / seconds / 1e6 << " M rays/s, " << simulated_s / seconds
            << "x real time\n";
  // Every scan completed by the poll's time (the last one or two are still being measured).
  EXPECT_GE(simulated_s, 2.0 - 2.0 / lidar_.scan_rate_hz - 1e-9);
  EXPECT_LE(simulated_s, 2.0 + 1e-9);
  EXPECT_EQ(scans.front().utime, kFirstScanUtime);
  for (size_t k = 1; k < scans.size(); ++k) {
    EXPECT_EQ(scans[k].utime - scans[k - 1].utime, int64_t(1e6 / lidar_.scan_rate_hz + 0.5));
  }
}

}  // namespace
}  // namespace sweepmap
