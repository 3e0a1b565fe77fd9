// End to end through `sweepmap calib axis-offset --rig rig_a`: 4 mode-7 sweeps of the
// conference room simulated with a true lidar-to-axis offset of 16.0 mm against the rig's
// nominal 13.9 mm, calibrated (within 1 mm), written, pointed to by a rig file, and replayed
// with it: the replayed walls are flatter than with the nominal offset.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "calib/walls.hpp"
#include "core/calibration_file.hpp"
#include "mapping/cloud_io.hpp"
#include "tests/e2e/test_support.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
constexpr int kSweeps = 4;  // the 20 take 20-90 s to calibrate: measured in the README

// Runs build/bin/sweepmap with stdout and stderr in separate files (--json goes to stdout).
int runSplit(const std::vector<std::string>& args, const fs::path& out, const fs::path& err) {
  std::string cmd = binPath("sweepmap");
  for (const auto& a : args) cmd += " '" + a + "'";
  cmd += " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string offsetLog() {
  std::vector<std::string> a = {"--rig",    kRig,
                                "--mode",   "7",
                                "--sweeps", std::to_string(kSweeps),
                                "--seed",   "1",
                                "--set",    "sim.lidar_offset_x_mm=16.0"};
  const auto paper = paperModelArgs();  // the paper's model: the offset alone is off
  a.insert(a.end(), paper.begin(), paper.end());
  return cachedSimLog("mode7x4_offset16", a);
}

// RMS distance of the walls' points to their least-squares planes, the walls found on the
// nominal sweep and the same points (same order) taken from the calibrated one.
struct WallRms {
  double nominal_mm = 0, calibrated_mm = 0;
  size_t points = 0;
};

void addSweep(const std::vector<Eigen::Vector3f>& nominal,
              const std::vector<Eigen::Vector3f>& calibrated, double* ss_n, double* ss_c,
              size_t* n) {
  PlaneExtractionOptions o;
  o.orientation = PlaneExtractionOptions::Orientation::kVertical;
  o.max_planes = 4;
  for (const WallPlaneFit& w : extractPlanes(nominal, o)) {
    for (const auto* cloud : {&nominal, &calibrated}) {
      Eigen::Vector3d normal;
      double offset = 0;
      ASSERT_TRUE(fitPlaneLeastSquares(*cloud, w.inlier_indices, &normal, &offset));
      double ss = 0;
      for (int i : w.inlier_indices) {
        const double e = normal.dot((*cloud)[static_cast<size_t>(i)].cast<double>()) + offset;
        ss += e * e;
      }
      *(cloud == &nominal ? ss_n : ss_c) += ss;
    }
    *n += w.inlier_indices.size();
  }
}

WallRms wallRms(const fs::path& nominal_dir, const fs::path& calibrated_dir) {
  double ss_n = 0, ss_c = 0;
  size_t n = 0;
  for (const auto& entry : fs::directory_iterator(nominal_dir / "sweeps")) {
    if (entry.path().extension() != ".pcd") continue;
    const auto a = readPcd(entry.path().string());
    const auto b = readPcd((calibrated_dir / "sweeps" / entry.path().filename()).string());
    EXPECT_EQ(a.size(), b.size()) << entry.path();
    if (a.size() != b.size()) continue;
    addSweep(a, b, &ss_n, &ss_c, &n);
  }
  WallRms r;
  r.points = n;
  if (n > 0) {
    r.nominal_mm = 1e3 * std::sqrt(ss_n / static_cast<double>(n));
    r.calibrated_mm = 1e3 * std::sqrt(ss_c / static_cast<double>(n));
  }
  return r;
}

TEST(CalibAxisOffsetRigA, FindsTheTrueOffsetAndReplayUsesIt) {
  const std::string log = offsetLog();
  const fs::path dir = scratchDir("calib_axis_offset_rig_a");
  const fs::path out = dir / "offset.yaml";
  ASSERT_EQ(runSplit({"calib", "axis-offset", "--logs", log, "--rig", kRig, "--out", out.string(),
                      "--json"},
                     dir / "stdout.json", dir / "stderr.txt"),
            0)
      << readFile(dir / "stderr.txt");
  const nlohmann::json j = readJson(dir / "stdout.json");
  const double x = j.at("lidar_offset_x_mm").get<double>();
  std::printf(
      "calib axis-offset, %d mode-7 sweeps: x = %.4f +- %.4f mm (truth %.1f), wall RMS "
      "%.4f -> %.4f mm, observability x %.3f y %.3f z %.2g\n",
      kSweeps, x, j.at("sigma_x_mm").get<double>(), j.at("truth_x_mm").get<double>(),
      j.at("wall_rms_before_mm").get<double>(), j.at("wall_rms_after_mm").get<double>(),
      j.at("observability").at("x").get<double>(), j.at("observability").at("y").get<double>(),
      j.at("observability").at("z").get<double>());
  EXPECT_DOUBLE_EQ(j.at("truth_x_mm").get<double>(), 16.0);
  EXPECT_NEAR(x, 16.0, 1.0);
  // Only the offset is off (the paper's model): calib rig's joint model agrees, no warning.
  EXPECT_EQ(j.at("warnings").dump().find("joint model"), std::string::npos) << j.at("warnings");
  EXPECT_LT(j.at("sigma_x_mm").get<double>(), 0.5);
  EXPECT_TRUE(j.at("observable").get<bool>());
  EXPECT_EQ(j.at("sweeps_used").get<int>(), kSweeps) << j.at("sweeps_rejected").dump();
  EXPECT_GE(j.at("walls").get<int>(), 4 * kSweeps);
  EXPECT_LT(j.at("observability").at("z").get<double>(), 1e-6);  // along the axis: never
  EXPECT_GT(j.at("observability").at("x").get<double>(), 0.01);
  EXPECT_LT(j.at("wall_rms_after_mm").get<double>(), j.at("wall_rms_before_mm").get<double>());
  EXPECT_NEAR(loadLidarOffsetCalibration(out.string()).lidar_offset_x_mm, x, 1e-8);

  // A rig file that points to the calibration (relative to itself), replayed.
  std::string rig_text = readFile(kRig);
  const std::string empty = "calibration_file: \"\"\n";
  const size_t at = rig_text.find(empty, rig_text.find("geometry:"));
  ASSERT_NE(at, std::string::npos);
  rig_text.replace(at, empty.size(), "calibration_file: offset.yaml\n");
  std::ofstream(dir / "rig.yaml") << rig_text;
  ASSERT_EQ(
      sweepmap({"replay", log, "--rig", (dir / "rig.yaml").string(), "--out",
                (dir / "calibrated").string(), "--no-plots", "--set", "mapper.resolution_m=0.5"},
               dir / "replay_calibrated.txt"),
      0)
      << readFile(dir / "replay_calibrated.txt");
  ASSERT_EQ(sweepmap({"replay", log, "--rig", kRig, "--out", (dir / "nominal").string(),
                      "--no-plots", "--set", "mapper.resolution_m=0.5"},
                     dir / "replay_nominal.txt"),
            0);
  const nlohmann::json sc = readJson(dir / "calibrated" / "summary.json");
  EXPECT_NEAR(sc.at("geometry").at("lidar_offset_x_mm").get<double>(), x, 1e-8);
  EXPECT_DOUBLE_EQ(sc.at("truth").at("lidar_offset_x_mm").get<double>(), 16.0);
  EXPECT_DOUBLE_EQ(readJson(dir / "nominal" / "summary.json")
                       .at("geometry")
                       .at("lidar_offset_x_mm")
                       .get<double>(),
                   13.9);
  const WallRms rms = wallRms(dir / "nominal", dir / "calibrated");
  std::printf("replayed walls (%zu points): RMS %.4f mm nominal -> %.4f mm calibrated\n",
              rms.points, rms.nominal_mm, rms.calibrated_mm);
  EXPECT_GT(rms.points, 100000u);
  EXPECT_LT(rms.calibrated_mm, rms.nominal_mm);
}

TEST(CalibAxisOffsetRigA, OptionsOfTheOtherKindAreRefused) {
  const fs::path dir = scratchDir("calib_axis_offset_rig_a_options");
  const std::string log = (dir / "x.lcmlog").string();  // exists: the options are checked first
  std::ofstream(log).flush();
  EXPECT_EQ(runSplit({"calib", "axis-offset", "--logs", log, "--rig", "rig_a", "--out",
                      (dir / "o.yaml").string(), "--step", "0.5"},
                     dir / "a.out", dir / "a.err"),
            2);
  EXPECT_NE(readFile(dir / "a.err").find("--step is for rotating_profile rigs"), std::string::npos)
      << readFile(dir / "a.err");
  EXPECT_EQ(runSplit({"calib", "axis-offset", "--logs", log, "--rig", "rig_c", "--out",
                      (dir / "o.yaml").string(), "--offset-y"},
                     dir / "c.out", dir / "c.err"),
            2);
  EXPECT_NE(readFile(dir / "c.err").find("--offset-y is for rotating_lidar rigs"),
            std::string::npos)
      << readFile(dir / "c.err");
  // A missing log is named (exit 2), nothing written.
  EXPECT_EQ(runSplit({"calib", "axis-offset", "--logs", (dir / "none.lcmlog").string(), "--rig",
                      "rig_a", "--out", (dir / "o.yaml").string()},
                     dir / "m.out", dir / "m.err"),
            2);
  EXPECT_NE(readFile(dir / "m.err").find("none.lcmlog"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "o.yaml"));
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
