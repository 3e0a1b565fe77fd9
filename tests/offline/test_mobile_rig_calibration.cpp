// Rig B's joint calibration (tools/offline/mobile_rig_calibration.hpp) on calib plan's drive
// (a figure-eight with stops) with every build error of the simulator at its default (wheel
// radii, track, lever arm, clock offset, gyro bias, mounting): the targets (mounting
// within 0.3 mrad per axis, wheel radii within 0.1 %, the room within 3 mm) and the truth
// within 3 sigma.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "core/event_log.hpp"
#include "tools/offline/mobile_rig_calibration.hpp"
#include "tools/offline/runs.hpp"
#include "tools/offline/sim_mobile.hpp"

namespace sweepmap {
namespace {

const std::string kRig = std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b.yaml";
const std::string kScene = std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_lab.yaml";

std::string simulate(double duration_s, uint64_t seed, const std::vector<std::string>& drive) {
  const std::string dir = std::string(SWEEPMAP_BINARY_DIR) + "/test_scratch/mobile_rig_calib";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/seed" + std::to_string(seed) + ".lcmlog";
  std::vector<std::string> sets = drive;
  sets.push_back("sim.duration_s=" + std::to_string(duration_s));
  const SimSetup setup = loadSimSetup(kRig, kScene, sets);
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
  for (const char* key : {"mounting.gamma_rad", "mounting.beta_rad", "mounting.alpha_rad"}) {
    const CalibParameter& p = find(r, key);
    ASSERT_TRUE(p.truth.has_value());
    EXPECT_TRUE(p.observable) << key;
    EXPECT_NEAR(p.value, *p.truth, 3e-4) << key;
  }
  for (const char* key : {"odometry.wheel_radius_m", "odometry.wheel_radius_right_m"}) {
    const CalibParameter& p = find(r, key);
    EXPECT_TRUE(p.observable) << key;
    EXPECT_NEAR(p.value / *p.truth, 1.0, 1e-3) << key;
  }
  // Every parameter the drive determines: the truth within 3 sigma.
  for (const auto& p : r.parameters) {
    if (p.observable && p.truth) EXPECT_NEAR(p.value, *p.truth, 3 * p.sigma) << p.key;
  }
  ASSERT_EQ(r.measures.size(), 3u);
  for (const auto& m : r.measures) {
    ASSERT_TRUE(m.truth.has_value()) << m.key;
    EXPECT_NEAR(m.value, *m.truth, 3e-3) << m.key;
  }
}

}  // namespace
}  // namespace sweepmap
