// Rig B's joint calibration (tools/offline/mobile_rig_calibration.hpp) on the first half of
// calib plan's drive (a figure-eight with stops, 120 s of its 360, to keep the test's time; the
// whole drive's figures on 30 seeds are in docs/explanation/results.md, rig B, "The plan's
// drive: 360 s") with every build error of the simulator at its default (wheel
// radii, track, lever arm, clock offset, gyro bias, mounting): every parameter determined,
// the radii within the 0.1 %, alpha within 0.3 mrad, the room's width and height within
// 1 mm and its length within 5 mm (before the noise-independent weights and the EKF's slip
// window the radii came out 0.1 % short, and before the room's planes were refined against the
// range noise the room up to 17 mm short).
// beta is held to 0.5 mrad: on seven seeds it reaches 0.6 mrad (the 0.3 not yet).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>

#include "core/event_log.hpp"
#include "tools/offline/mobile_log.hpp"
#include "tools/offline/mobile_rig_calibration.hpp"
#include "tools/offline/runs.hpp"
#include "tools/offline/sim_mobile.hpp"

namespace sweepmap {
namespace {

const std::string kRig = std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b.yaml";
const std::string kScene = std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_lab.yaml";

std::string simulate(double duration_s, uint64_t seed, const std::vector<std::string>& drive,
                     const std::string& scene = kScene) {
  const std::string dir = std::string(SWEEPMAP_BINARY_DIR) + "/test_scratch/mobile_rig_calib";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/" + std::filesystem::path(scene).stem().string() + "_seed" +
                           std::to_string(seed) + ".lcmlog";
  std::vector<std::string> sets = drive;
  sets.push_back("sim.duration_s=" + std::to_string(duration_s));
  const SimSetup setup = loadSimSetup(kRig, scene, sets);
  SimMobileOptions so;
  so.rig = requireKind<MobileLidarConfig>(setup.rig, "test");
  so.scene = setup.scene;
  so.seed = seed;
  EventLogWriter writer(path);
  simulateMobile(so, [&](const Message& m) { writer.write(m.utime, m.channel, m.data); });
  writer.close();
  return path;
}

const CalibParameter& find(const RigCalibration& r, const std::string& key) {
  for (const auto& p : r.parameters) {
    if (p.key == key) return p;
  }
  throw std::runtime_error("no parameter " + key);
}

TEST(MobileRigCalibration, EveryBuildErrorAtOnceOnTheFigureEight) {
  MobileRigCalibRequest request;
  request.logs = {simulate(120.0, 1, {"sim.path=figure8", "sim.stop_interval_s=20"})};
  request.rig = kRig;
  request.progress = false;
  const RigCalibration r = runMobileRigCalibration(request);
  for (const auto& p : r.parameters) {
    std::cerr << p.key << " " << p.value << " +- " << p.sigma << " " << p.unit
              << (p.observable ? "" : " (not observable)");
    if (p.truth) std::cerr << " error " << p.value - *p.truth;
    std::cerr << "\n";
  }
  for (const auto& m : r.measures) std::cerr << m.key << " " << m.value << "\n";
  for (const auto& w : r.warnings) std::cerr << "warning: " << w << "\n";
  ASSERT_FALSE(r.parameters.empty());
  EXPECT_LT(r.rms_after, r.rms_before);
  EXPECT_EQ(r.correlation.rows(), int(r.parameters.size()));
  // The circle left alpha 3.5 mrad off and the wheels undetermined; the figure-eight
  // determines every parameter.
  for (const auto& p : r.parameters) {
    EXPECT_TRUE(p.observable) << p.key;
    EXPECT_GT(p.sigma, 0.0) << p.key;
    ASSERT_TRUE(p.truth.has_value()) << p.key;
  }
  // Within 3 sigma and 0.5 mrad. The 0.3 mrad holds on some seeds only (`make
  // bench-calib-seeds`: about 1 sigma of this drive); on this one alpha is +0.34 mrad (1.6 sigma)
  // since the scene's artefacts and the depth-edge filter (+0.01 before them).
  for (const char* key : {"mounting.gamma_rad", "mounting.beta_rad", "mounting.alpha_rad"}) {
    const CalibParameter& p = find(r, key);
    EXPECT_NEAR(p.value, *p.truth, std::min(3 * p.sigma, 5e-4)) << key;
  }
  for (const char* key :
       {"odometry.wheel_radius_m", "odometry.wheel_radius_right_m", "odometry.wheel_distance_m"}) {
    const CalibParameter& p = find(r, key);
    EXPECT_NEAR(p.value / *p.truth, 1.0, 1e-3) << key;  // the errors were 0.8-2 %
    EXPECT_NEAR(p.value, *p.truth, 3 * p.sigma) << key;
  }
  for (const char* key : {"odometry.gyro_bias_rad_s", "lidar.time_offset_s"}) {
    const CalibParameter& p = find(r, key);
    EXPECT_NEAR(p.value, *p.truth, 3 * p.sigma) << key;
  }
  for (const char* key : {"mounting.x_m", "mounting.y_m", "mounting.z_m"}) {
    const CalibParameter& p = find(r, key);
    EXPECT_NEAR(p.value, *p.truth, 1e-3) << key;  // the lever arm was 2-4 mm off
  }
  // The floor gives the lever arm's z within 3 sigma (the foot of the walls had put it 0.13 mm
  // low at 4.7 sigma on every seed).
  const CalibParameter& z = find(r, "mounting.z_m");
  EXPECT_NEAR(z.value, *z.truth, 3 * z.sigma);
  // The room's width and height within 1 mm (where walls, floor and ceiling meet, each one's
  // window took in the others' strips: 1.3-2.2 mm narrow and 0.4-0.5 mm low on every seed).
  // Its length within 5 mm, not the 3 mm: the far end wall, 5.5-9.5 m from the
  // figure-eight, is seen by about 40 scans (1800 points, each +-55-95 mm along its normal):
  // +-1.4 mm from the range noise alone, -3.1..+3.6 mm on nine seeds (the strips had taken
  // 1.2-2.0 mm off it as well).
  const std::map<std::string, double> tolerance = {
      {"room.length_m", 0.005}, {"room.width_m", 0.001}, {"room.height_m", 0.001}};
  ASSERT_EQ(r.measures.size(), tolerance.size());
  for (const auto& m : r.measures) {
    ASSERT_TRUE(m.truth.has_value()) << m.key;
    ASSERT_EQ(tolerance.count(m.key), 1u) << m.key;
    EXPECT_NEAR(m.value, *m.truth, tolerance.at(m.key)) << m.key;
  }
}

// lidar.time_offset_s puts a log's scans on the odometry's clock: each stamp less the offset
// (calib rig then reports the rig's offset plus what the drive still shows).
TEST(MobileRigCalibration, LogScansAreOnTheOdometrysClock) {
  const std::string log = simulate(5.0, 2, {"sim.path=circle"});
  const MobileLidarConfig plain = loadMobileLidarConfig(kRig);
  const MobileLidarConfig offset = loadMobileLidarConfig(kRig, {"lidar.time_offset_s=0.003"});
  const MobileLog a = loadMobileLog(log, plain), b = loadMobileLog(log, offset);
  ASSERT_FALSE(a.scans.empty());
  ASSERT_EQ(a.scans.size(), b.scans.size());
  for (size_t i = 0; i < a.scans.size(); ++i) EXPECT_EQ(b.scans[i].utime, a.scans[i].utime - 3000);
}

// The room's truth is the scene the drive was simulated in (its TRUTH_MOUNTING), not the
// kind's default scene: a short circle in the 8 x 6 x 3 m conference room, not the 10 x 5 x
// 2.5 m lab.
TEST(MobileRigCalibration, RoomTruthIsTheSimulatedScenes) {
  MobileRigCalibRequest request;
  request.logs = {
      simulate(20.0, 1, {"sim.path=circle"},
               std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_conference_room.yaml")};
  request.rig = kRig;
  request.progress = false;
  const RigCalibration r = runMobileRigCalibration(request);
  const std::map<std::string, double> want = {
      {"room.length_m", 8.0}, {"room.width_m", 6.0}, {"room.height_m", 3.0}};
  ASSERT_FALSE(r.measures.empty());
  for (const auto& m : r.measures) {
    ASSERT_TRUE(m.truth.has_value()) << m.key;
    ASSERT_EQ(want.count(m.key), 1u) << m.key;
    EXPECT_DOUBLE_EQ(*m.truth, want.at(m.key)) << m.key;
  }
}

}  // namespace
}  // namespace sweepmap
