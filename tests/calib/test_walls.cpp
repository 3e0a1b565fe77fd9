// Wall extraction (Yuan 2021 Fig. 7) on a synthetic room and on a simulated mode-7 sweep.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <random>

#include "calib/rotating_geometry.hpp"
#include "calib/walls.hpp"
#include "core/angles.hpp"
#include "core/event_log.hpp"
#include "core/rig_components.hpp"
#include "sim/scene.hpp"
#include "tools/offline/log_sweeps.hpp"
#include "tools/offline/runs.hpp"

namespace sweepmap {
namespace {

std::string sourcePath(const std::string& rel) {
  return std::string(SWEEPMAP_SOURCE_DIR) + "/" + rel;
}

// What `sweepmap sim --rig <rig> --scene <scene> --mode <mode> --sweeps 1 --seed <seed> --out
// LOG` writes, made in this process through the same library calls (same seed, same log).
std::string simulatedLog(const std::string& name, const std::string& rig_path,
                         const std::string& scene_path, int mode, uint64_t seed) {
  const std::filesystem::path dir =
      std::filesystem::path(SWEEPMAP_BINARY_DIR) / "test_scratch" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string log_path = (dir / "sim.lcmlog").string();
  // The paper's error model: a tilted scan plane or a mirror offset would turn the walls by
  // more than this test's bound, and that is what `calib rig` measures, not wall extraction.
  std::vector<std::string> sets = SimRigConfig::paperSettings();
  sets.push_back("motor.mode=" + std::to_string(mode));
  const SimSetup setup = loadSimSetup(rig_path, scene_path, sets);
  SimRunOptions options;
  options.seed = seed;
  options.sweeps = 1;
  EventLogWriter log(log_path);
  const SimRunResult r =
      simulateRig(setup, options, [&](const Message& m) { log.write(m.utime, m.channel, m.data); });
  log.close();
  if (!r.ok) throw std::runtime_error("simulation failed: " + r.summary);
  return log_path;
}

double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) / kDegToRad;
}

// Points on an axis-aligned rectangle: `fixed` axis at `value`, the other two spanning
// [lo, hi], on a grid of `step` with Gaussian noise along the fixed axis.
void addRect(std::vector<Eigen::Vector3f>* cloud, int fixed, double value, Eigen::Vector3d lo,
             Eigen::Vector3d hi, double step, std::mt19937* rng, double sigma = 0.012) {
  std::normal_distribution<double> noise(0.0, sigma);
  const int u = (fixed + 1) % 3, v = (fixed + 2) % 3;
  for (double a = lo[u]; a <= hi[u]; a += step) {
    for (double b = lo[v]; b <= hi[v]; b += step) {
      Eigen::Vector3d p;
      p[fixed] = value + noise(*rng);
      p[u] = a;
      p[v] = b;
      cloud->push_back(p.cast<float>());
    }
  }
}

// A room seen from the sensor at the origin (frame O): walls at x = -5.2, 2.8 and
// y = -3.8, 2.2; floor z = -1, ceiling z = 2; a door recess (0.3 m deep) in the +Y wall
// and a cabinet front 0.45 m before the -Y wall. The whole cloud is turned by `yaw`.
std::vector<Eigen::Vector3f> syntheticRoom(double yaw_rad, uint32_t seed = 1) {
  std::mt19937 rng(seed);
  std::vector<Eigen::Vector3f> c;
  const double s = 0.03;
  addRect(&c, 0, -5.2, {0, -3.8, -1}, {0, 2.2, 2}, s, &rng);
  addRect(&c, 0, 2.8, {0, -3.8, -1}, {0, 2.2, 2}, s, &rng);
  addRect(&c, 1, -3.8, {-5.2, 0, -1}, {2.8, 0, 2}, s, &rng);
  // +Y wall with the door opening x in [0.8, 1.8], z < 1.1; the door leaf 0.3 m behind.
  addRect(&c, 1, 2.2, {-5.2, 0, -1}, {0.8, 0, 2}, s, &rng);
  addRect(&c, 1, 2.2, {1.8, 0, -1}, {2.8, 0, 2}, s, &rng);
  addRect(&c, 1, 2.2, {0.8, 0, 1.1}, {1.8, 0, 2}, s, &rng);
  addRect(&c, 1, 2.5, {0.8, 0, -1}, {1.8, 0, 1.1}, s / 2, &rng);
  // Cabinet front (denser than the walls, as a near surface is) and top.
  addRect(&c, 1, -3.35, {0.6, 0, -1}, {1.8, 0, -0.1}, s / 2, &rng);
  addRect(&c, 2, -0.1, {0.6, -3.8, 0}, {1.8, -3.35, 0}, s, &rng);
  addRect(&c, 2, -1.0, {-5.2, -3.8, 0}, {2.8, 2.2, 0}, s, &rng);
  addRect(&c, 2, 2.0, {-5.2, -3.8, 0}, {2.8, 2.2, 0}, s, &rng);
  const Eigen::Matrix3f R = rotating::rotZ(yaw_rad).cast<float>();
  for (auto& p : c) p = R * p;
  return c;
}

TEST(WallExtraction, FindsTheFourWallsOfASyntheticRoomInOrder) {
  const double yaw = 3 * kDegToRad;
  const auto cloud = syntheticRoom(yaw);
  const WallExtraction e = extractWalls(cloud);
  ASSERT_EQ(e.walls.size(), 4u) << e.reason;
  const Eigen::Matrix3d R = rotating::rotZ(yaw);
  // Order: normals +Y, +X, -Y, -X (pointing toward the sensor); distances from the origin.
  const Eigen::Vector3d normals[4] = {R * Eigen::Vector3d::UnitY(), R * Eigen::Vector3d::UnitX(),
                                      R * -Eigen::Vector3d::UnitY(), R * -Eigen::Vector3d::UnitX()};
  const double offsets[4] = {3.8, 5.2, 2.2, 2.8};
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(k);
    EXPECT_LT(angleDeg(e.walls[k].normal, normals[k]), 0.05);
    EXPECT_NEAR(e.walls[k].offset, offsets[k], 0.01);  // not the cabinet (3.35), not the door (2.5)
    EXPECT_NEAR(e.walls[k].rms_m, 0.012, 0.003);
    EXPECT_EQ(e.walls[k].inliers, static_cast<int>(e.walls[k].inlier_indices.size()));
    for (int i : e.walls[k].inlier_indices) {
      ASSERT_LE(std::abs(e.walls[k].normal.dot(cloud[i].cast<double>()) + e.walls[k].offset), 0.03);
    }
  }
}

TEST(WallExtraction, IsDeterministic) {
  const auto cloud = syntheticRoom(-7 * kDegToRad, 2);
  const WallExtraction a = extractWalls(cloud);
  const WallExtraction b = extractWalls(cloud);
  ASSERT_EQ(a.walls.size(), 4u) << a.reason;
  ASSERT_EQ(b.walls.size(), 4u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(a.walls[k].normal, b.walls[k].normal);
    EXPECT_EQ(a.walls[k].inlier_indices, b.walls[k].inlier_indices);
  }
}

TEST(WallExtraction, CloudWithoutFourWallsGivesAReason) {
  std::mt19937 rng(4);
  std::vector<Eigen::Vector3f> c;
  addRect(&c, 2, -1.0, {-5, -4, 0}, {3, 2, 0}, 0.03, &rng);     // floor
  addRect(&c, 0, 2.8, {0, -3.8, -1}, {0, 2.2, 2}, 0.03, &rng);  // one wall
  addRect(&c, 1, 2.2, {-5.2, 0, -1}, {2.8, 0, 2}, 0.03, &rng);  // and its neighbour
  const WallExtraction e = extractWalls(c);
  EXPECT_TRUE(e.walls.empty());
  EXPECT_FALSE(e.reason.empty());
  EXPECT_EQ(e.candidate_planes, 2);

  std::uniform_real_distribution<float> u(-3, 3);
  std::vector<Eigen::Vector3f> blob(20000);
  for (auto& p : blob) p = Eigen::Vector3f(u(rng), u(rng), u(rng));
  const WallExtraction b = extractWalls(blob);
  EXPECT_TRUE(b.walls.empty());
  EXPECT_FALSE(b.reason.empty());

  EXPECT_EQ(extractWalls({}).reason, "empty cloud");
}

TEST(WallExtraction, RefitOnFullCloudKeepsOrientation) {
  const auto cloud = syntheticRoom(0);
  WallPlaneFit rough;
  rough.normal =
      Eigen::AngleAxisd(0.5 * kDegToRad, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(-1, 0, 0);
  rough.offset = 2.8;
  const auto refit = refitWalls(cloud, {rough}, 0.05);
  ASSERT_EQ(refit.size(), 1u);
  EXPECT_LT(angleDeg(refit[0].normal, Eigen::Vector3d(-1, 0, 0)), 0.05);
  EXPECT_NEAR(refit[0].offset, 2.8, 0.005);
  EXPECT_GT(refit[0].inliers, 10000);
}

// One simulated mode-7 sweep of the conference room (as sweepmap sim): the four walls are
// found, their normals match the scene's truth turned by the sweep's residual attitude
// error, and neither the door recess nor the cabinet front is taken for a wall.
TEST(WallExtraction, SimulatedConferenceRoomSweep) {
  const std::string rig_path = sourcePath("config/rig_a.yaml");
  const std::string scene_path = sourcePath("config/scene_conference_room.yaml");
  const std::string log = simulatedLog("mode7x1_walls", rig_path, scene_path, 7, 5);
  const RotatingLidarConfig rig = loadRotatingLidarConfig(rig_path);
  const SceneConfig scene_config = loadScene(scene_path);
  const Scene scene(scene_config, rig.plate);
  int sweeps = 0;
  forEachSweep(log, rig, [&](const AssembledSweep& s, const SweepTruth& truth) {
    ++sweeps;
    ASSERT_TRUE(s.corrected) << s.reason;
    ASSERT_TRUE(truth.phi_true_rad.has_value());
    const auto t0 = std::chrono::steady_clock::now();
    const WallExtraction e = extractWalls(s.points);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::cout << "extractWalls: " << s.points.size() << " points, " << ms << " ms\n";
    ASSERT_EQ(e.walls.size(), 4u) << e.reason;
    // Assembled C_O = R_z(phi_offset - phi_true) * true C_O.
    const double phi_error = wrapAngle(s.phi_offset_rad - *truth.phi_true_rad);
    const Eigen::Matrix3d R_err = rotating::rotZ(phi_error);
    const Eigen::Isometry3d T_room_O = scene.T_room_rig();
    const char* want[4] = {"y_min", "x_min", "y_max", "x_max"};  // normals +Y, +X, -Y, -X
    for (int k = 0; k < 4; ++k) {
      SCOPED_TRACE(want[k]);
      const WallPlane* truth_wall = nullptr;
      for (const auto& w : scene.wallPlanes()) {
        if (w.name == want[k]) truth_wall = &w;
      }
      ASSERT_NE(truth_wall, nullptr);
      const Eigen::Vector3d n_O = T_room_O.linear().transpose() * truth_wall->normal;
      const double d_O = truth_wall->offset + truth_wall->normal.dot(T_room_O.translation());
      const Eigen::Vector3d n_meas = e.walls[k].normal;
      std::cout << want[k] << ": angle to truth " << angleDeg(n_meas, n_O)
                << " deg, to R_err truth " << angleDeg(n_meas, R_err * n_O) << " deg, offset "
                << e.walls[k].offset << " m (true " << d_O << "), rms " << e.walls[k].rms_m * 1e3
                << " mm, inliers " << e.walls[k].inliers << "\n";
      EXPECT_LT(angleDeg(n_meas, n_O), 1.0);
      EXPECT_LT(angleDeg(n_meas, R_err * n_O), 0.1);
      EXPECT_NEAR(e.walls[k].offset, d_O, 0.05);  // door leaf 0.3 m, cabinet 0.45 m away
    }
  });
  EXPECT_EQ(sweeps, 1);
}

}  // namespace
}  // namespace sweepmap
