// Rig B's joint calibration (tools/offline/mobile_rig_calibration.hpp) on a simulated drive
// with every build error of the simulator at its default (wheel radii, track, lever arm,
// clock offset, gyro bias, mounting): what it determines within 3 sigma of the truth, what it
// cannot reported and left nominal.
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

std::string simulate(double duration_s, uint64_t seed) {
  const std::string dir = std::string(SWEEPMAP_BINARY_DIR) + "/test_scratch/mobile_rig_calib";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/seed" + std::to_string(seed) + ".lcmlog";
  const std::vector<std::string> sets = {"sim.duration_s=" + std::to_string(duration_s)};
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

TEST(MobileRigCalibration, EveryBuildErrorAtOnceOnTheCalibrationCircle) {
  MobileRigCalibRequest request;
  request.logs = {simulate(60.0, 1)};
  request.rig = kRig;
  request.progress = false;
  const RigCalibration r = runMobileRigCalibration(request);
  for (const auto& p : r.parameters) {
    std::cerr << p.key << " " << p.value << " +- " << p.sigma << " " << p.unit
              << (p.observable ? "" : " (not observable)");
    if (p.truth) std::cerr << " error " << p.value - *p.truth;
    std::cerr << "\n";
  }
  for (const auto& w : r.warnings) std::cerr << "warning: " << w << "\n";
  ASSERT_FALSE(r.parameters.empty());
  EXPECT_LT(r.rms_after, r.rms_before);
  // On the circle alone, gamma and beta are determined within 3 sigma of the truth. (alpha
  // is not: it shares the antipodal shift with the wheels' scale and the lever arm, which a
  // circle cannot tell apart; see the report of issue 23.)
  for (const char* key : {"mounting.gamma_rad", "mounting.beta_rad"}) {
    const CalibParameter& p = find(r, key);
    ASSERT_TRUE(p.truth.has_value());
    EXPECT_TRUE(p.observable) << key;
    EXPECT_GT(p.sigma, 0.0) << key;
    EXPECT_NEAR(p.value, *p.truth, 3 * p.sigma) << key;
  }
  // What the drive cannot determine is reported and left at the rig file's value.
  const CalibParameter& z = find(r, "mounting.z_m");
  EXPECT_FALSE(z.observable);
  EXPECT_EQ(z.value, 0.30);
  EXPECT_EQ(z.sigma, 0.0);
  bool warned = false;
  for (const auto& w : r.warnings) warned = warned || w.find("mounting.z_m") != std::string::npos;
  EXPECT_TRUE(warned);
  EXPECT_EQ(r.correlation.rows(), int(r.parameters.size()));
}

}  // namespace
}  // namespace sweepmap
