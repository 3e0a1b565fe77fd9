// End to end through `sweepmap calib rig --rig rig_a` (issue 23): a short recording of the
// simulated rig with every error of a real build at its default (tilted scan plane, mirror
// offset, plate installation error and thickness, offset 16 mm against the rig's 13.9) and the
// scene's artefacts (mixed pixels, dropouts, people, a window, a whiteboard); every parameter
// within 3 sigma of the truth, the file written and applied by the rig file's
// calibration_file; other kinds refused with exit 2; `calib plan` prints its sim command.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/calibration_file.hpp"
#include "rigs/rotating_lidar.hpp"
#include "tests/e2e/test_support.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");

int runSplit(const std::vector<std::string>& args, const fs::path& out, const fs::path& err) {
  std::string cmd = binPath("sweepmap");
  for (const auto& a : args) cmd += " '" + a + "'";
  cmd += " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string readAll(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// 3 mode-7 sweeps (the plan's 10 take longer; their figures are in the explanation).
std::string realisticLog() {
  return cachedSimLog("calib_rig_mode7x3", {"--rig", kRig, "--mode", "7", "--sweeps", "3", "--seed",
                                            "3", "--set", "sim.lidar_offset_x_mm=16"});
}

TEST(CalibRig, EveryParameterOfARealisticBuildWithinThreeSigmaAndApplied) {
  const fs::path dir = scratchDir("calib_rig");
  const fs::path calib = dir / "rig_calibration.yaml";
  ASSERT_EQ(runSplit({"calib", "rig", "--rig", kRig, "--logs", realisticLog(), "--out",
                      calib.string(), "--json"},
                     dir / "out.json", dir / "err.txt"),
            0)
      << readAll(dir / "err.txt");
  const auto j = nlohmann::json::parse(readAll(dir / "out.json"));
  for (const char* key : {"plate.alpha_deg", "geometry.lidar_offset_x_mm",
                          "geometry.scan_plane_tilt_deg", "geometry.mirror_offset_deg"}) {
    SCOPED_TRACE(key);
    const auto& p = j["parameters"][key];
    ASSERT_TRUE(p["observable"].get<bool>()) << p;
    const double value = p["value"], sigma = p["sigma"], truth = p["truth"];
    EXPECT_GT(sigma, 0.0);
    EXPECT_LE(std::fabs(value - truth), 3.0 * sigma) << p;
  }
  // The rig file's calibration_file applies every key (relative to the rig file's folder).
  std::string rig_text = readAll(kRig);
  rig_text.replace(rig_text.find("calibration_file: \"\""), 20,
                   "calibration_file: " + calib.filename().string());
  std::ofstream(dir / "my_rig.yaml") << rig_text;
  const RotatingLidarConfig rig = loadRotatingLidarConfig((dir / "my_rig.yaml").string());
  // (The file holds 12 significant digits.)
  EXPECT_NEAR(rig.plate.alpha_deg, j["parameters"]["plate.alpha_deg"]["value"].get<double>(), 1e-9);
  EXPECT_NEAR(rig.geometry.scan_plane_tilt_deg,
              j["parameters"]["geometry.scan_plane_tilt_deg"]["value"].get<double>(), 1e-9);
}

TEST(CalibRig, OtherKindsAreNotYetSupported) {
  const fs::path dir = scratchDir("calib_rig_kinds");
  EXPECT_EQ(runSplit({"calib", "rig", "--rig", "rig_b", "--logs", realisticLog(), "--out",
                      (dir / "c.yaml").string()},
                     dir / "out.txt", dir / "err.txt"),
            2);
  EXPECT_NE(readAll(dir / "err.txt").find("not yet supported"), std::string::npos);
}

TEST(CalibRig, PlanPrintsTheRecordingAndItsSimCommand) {
  const fs::path dir = scratchDir("calib_plan");
  ASSERT_EQ(runSplit({"calib", "plan", "--rig", "rig_a"}, dir / "out.txt", dir / "err.txt"), 0);
  const std::string plan = readAll(dir / "out.txt");
  EXPECT_NE(plan.find("sweepmap sim --rig rig_a --set motor.mode=7 --sweeps 10"), std::string::npos)
      << plan;
  EXPECT_NE(plan.find("Why"), std::string::npos);
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
