// End to end through `sweepmap calib plate-angle`: 50 simulated mode-7 sweeps of the
// conference room (the paper's protocol) with the plate's installation error on
// (sim.alpha_true_deg 29.3598 vs plate.alpha_deg 30), calibrated, written, loaded back.
// And `sweepmap calib mounting` (rig B): a 120 s circle in the lab,
// slip and noise on, the EKF track replayed from the log.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <fstream>

#include "core/calibration_file.hpp"
#include "core/set_arguments.hpp"
#include "rigs/mobile_lidar.hpp"
#include "rigs/rotating_lidar.hpp"
#include "tests/e2e/test_support.hpp"

extern char** environ;

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");

// Runs build/bin/sweepmap with stdout and stderr in separate files (--json goes to stdout).
int runSplit(const std::vector<std::string>& args, const fs::path& out, const fs::path& err) {
  std::vector<std::string> argv = {binPath("sweepmap")};
  argv.insert(argv.end(), args.begin(), args.end());
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> cargs;
  for (auto& a : argv) cargs.push_back(a.data());
  cargs.push_back(nullptr);
  pid_t pid;
  const int spawned = posix_spawn(&pid, cargs[0], &fa, nullptr, cargs.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (spawned != 0) return -1;
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// 50 mode-7 sweeps, seed 31, default error model: ~1000 s simulated, shared by the tests.
std::string calibLog() {
  std::vector<std::string> a = {"--rig", kRig,       "--scene", kScene,   "--mode",
                                "7",     "--sweeps", "50",      "--seed", "31"};
  const auto paper = paperModelArgs();  // the paper's error model
  a.insert(a.end(), paper.begin(), paper.end());
  return cachedSimLog("mode7x50_calib", a);
}

TEST(CalibCli, PlateAngleFromFiftyMode7Sweeps) {
  const std::string log = calibLog();
  const fs::path dir = scratchDir("calib_cli_plate_angle");
  const fs::path out = dir / "plate_calibration.yaml";
  const auto t0 = std::chrono::steady_clock::now();
  const int rc = runSplit(
      {"calib", "plate-angle", "--logs", log, "--rig", kRig, "--out", out.string(), "--json"},
      dir / "stdout.json", dir / "stderr.txt");
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(rc, 0) << readFile(dir / "stderr.txt");
  const nlohmann::json j = readJson(dir / "stdout.json");

  const double alpha = j.at("alpha_deg").get<double>();
  ASSERT_TRUE(j.contains("alpha_true_deg")) << "the simulated log carries the true alpha";
  const double alpha_true = j.at("alpha_true_deg").get<double>();
  EXPECT_NEAR(alpha_true, 29.3598, 1e-9);
  std::cout << "calib plate-angle: alpha " << alpha << " deg, true " << alpha_true << " deg, error "
            << alpha - alpha_true << " deg, " << j.at("sweeps_used") << " sweeps used, "
            << j.at("iterations") << " LM iterations, wall time " << wall_s
            << " s (tool: " << j.at("timing_s").dump() << ")\n";
  EXPECT_LE(std::abs(alpha - alpha_true), 0.05);
  EXPECT_TRUE(j.at("converged").get<bool>()) << j.at("stop_reason");
  EXPECT_GE(j.at("sweeps_used").get<int>(), 45) << j.at("sweeps_rejected").dump(2);
  EXPECT_EQ(j.at("sweeps_used").get<size_t>() + j.at("sweeps_rejected").size(), 50u);
  EXPECT_LT(j.at("e_atti_mean_after").get<double>(), j.at("e_atti_mean_before").get<double>());

  // History: starts at alpha_0 = 30 deg, cost never increases, ends at the result.
  const auto& h = j.at("history");
  ASSERT_EQ(h.size(), j.at("iterations").get<size_t>() + 1);
  EXPECT_DOUBLE_EQ(h.front().at("alpha_deg").get<double>(), 30.0);
  for (size_t i = 1; i < h.size(); ++i) {
    EXPECT_LE(h[i].at("cost").get<double>(), h[i - 1].at("cost").get<double>());
  }
  EXPECT_DOUBLE_EQ(h.back().at("alpha_deg").get<double>(), alpha);

  // The calibration file loads, and a rig pointing to it uses its alpha.
  const PlateCalibration c = loadPlateCalibration(out.string());
  EXPECT_NEAR(c.alpha_deg, alpha, 1e-9);
  EXPECT_EQ(c.source.at("tool"), "sweepmap calib plate-angle");
  EXPECT_EQ(c.source.at("sweeps_used"), std::to_string(j.at("sweeps_used").get<int>()));
  EXPECT_EQ(c.source.at("iterations"), std::to_string(j.at("iterations").get<int>()));
  // A function of the logs only (issue 23: the same logs give byte-identical files): no date.
  EXPECT_EQ(c.source.count("date"), 0u);
  EXPECT_EQ(c.source.count("final_cost"), 1u);
  EXPECT_EQ(c.logs, std::vector<std::string>{log});

  std::string rig_text = readFile(kRig);
  // plate.calibration_file (geometry: has a key of the same name before it).
  const std::string key = "calibration_file: \"\"";
  const size_t plate = rig_text.find("\nplate:");
  ASSERT_NE(plate, std::string::npos);
  const size_t at = rig_text.find(key, plate);
  ASSERT_NE(at, std::string::npos);
  rig_text.replace(at, key.size(), "calibration_file: plate_calibration.yaml");
  std::ofstream(dir / "rig.yaml") << rig_text;
  const RotatingLidarConfig rig = loadRotatingLidarConfig((dir / "rig.yaml").string());
  EXPECT_NEAR(rig.plate.alpha_deg, alpha, 1e-9);
}

TEST(CalibCli, BadInputsFailWithAClearMessage) {
  const fs::path dir = scratchDir("calib_cli_bad");
  const fs::path out = dir / "c.yaml";
  // A log that is not an LCM log: no usable sweep, exit 1, nothing written.
  std::ofstream(dir / "garbage.lcmlog") << "this is not an lcm log, just some bytes";
  int rc = runSplit({"calib", "plate-angle", "--logs", (dir / "garbage.lcmlog").string(), "--rig",
                     kRig, "--out", out.string()},
                    dir / "o1.txt", dir / "e1.txt");
  EXPECT_NE(rc, 0);
  std::string err = readFile(dir / "e1.txt");
  EXPECT_NE(err.find("garbage.lcmlog"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));

  // A log that does not exist: exit 2, named.
  rc = runSplit({"calib", "plate-angle", "--logs", (dir / "missing.lcmlog").string(), "--rig", kRig,
                 "--out", out.string()},
                dir / "o2.txt", dir / "e2.txt");
  EXPECT_EQ(rc, 2);
  err = readFile(dir / "e2.txt");
  EXPECT_NE(err.find("missing.lcmlog"), std::string::npos) << err;

  // A bad rig key: exit 2, naming the key.
  rc = runSplit({"calib", "plate-angle", "--logs", (dir / "garbage.lcmlog").string(), "--rig", kRig,
                 "--out", out.string(), "--set", "plate.no_such_key=1"},
                dir / "o3.txt", dir / "e3.txt");
  EXPECT_EQ(rc, 2);
  EXPECT_NE(readFile(dir / "e3.txt").find("no_such_key"), std::string::npos);
  EXPECT_FALSE(fs::exists(out));
}

TEST(CalibCli, HelpDescribesTheGroupAndTheCommand) {
  const fs::path dir = scratchDir("calib_cli_help");
  ASSERT_EQ(runSplit({"calib", "--help"}, dir / "o1.txt", dir / "e1.txt"), 0);
  EXPECT_NE(readFile(dir / "o1.txt").find("plate-angle"), std::string::npos);
  ASSERT_EQ(runSplit({"calib", "plate-angle", "--help"}, dir / "o2.txt", dir / "e2.txt"), 0);
  const std::string help = readFile(dir / "o2.txt");
  for (const char* s : {"--logs", "--rig", "--out", "--json", "--set", "Algorithm A1"}) {
    EXPECT_NE(help.find(s), std::string::npos) << s << " missing in:\n" << help;
  }
}

// ---------------------------------------------------------------------------------------
// calib mounting (rig B).

const std::string kRigB = sourcePath("config/rig_b.yaml");

// The simulator's defaults for a calibration drive: the circle in the lab for 120 s (4.6
// laps, as the paper experiment's), slip and noise on, true mounting error (0.0355, 0.0126,
// -0.0058) rad; the rig file believes (0, 0, 0).
// A perfect build otherwise (wheels, track, lever arm and clocks as the rig file says): the
// single-parameter command assumes one, and with the build's errors alpha absorbs the wheels'
// scale (measured 4.1 mrad off); calibrating those too is rig B's joint calibration.
std::string circleLog() {
  std::vector<std::string> args = {"--rig",   kRigB,
                                   "--scene", sourcePath("config/scene_lab.yaml"),
                                   "--set",   "sim.duration_s=120"};
  appendSetArguments(
      &args, {"sim.wheel_radius_left_error_fraction=0", "sim.wheel_radius_right_error_fraction=0",
              "sim.wheel_distance_error_m=0", "sim.lever_error_x_m=0", "sim.lever_error_y_m=0",
              "sim.lever_error_z_m=0", "sim.lidar_time_offset_ms=0"});
  return cachedSimLog("circle_calibration_perfect_build", args);
}

TEST(CalibCli, MountingFromTheDefaultCircleWithin1Mrad) {
  const std::string log = circleLog();
  const fs::path dir = scratchDir("calib_cli_mounting");
  const fs::path out = dir / "mounting_calibration.yaml";
  const int rc = runSplit(
      {"calib", "mounting", "--logs", log, "--rig", kRigB, "--out", out.string(), "--json"},
      dir / "stdout.json", dir / "stderr.txt");
  ASSERT_EQ(rc, 0) << readFile(dir / "stderr.txt");
  const nlohmann::json j = readJson(dir / "stdout.json");
  std::cerr << readFile(dir / "stderr.txt");
  EXPECT_EQ(j.at("method"), "point_to_plane");
  EXPECT_EQ(j.at("track"), "ekf");
  const nlohmann::json truth = j.at("truth");
  EXPECT_NEAR(truth.at("gamma_rad").get<double>(), 0.0355, 1e-12);
  for (const char* a : {"gamma_rad", "beta_rad", "alpha_rad"}) {
    EXPECT_NEAR(j.at(a).get<double>(), truth.at(a).get<double>(), 1e-3) << a;
    // Each angle's sigma, from the covariance: a fraction of a milliradian on this drive.
    const double sigma = j.at("sigma").at(a).get<double>();
    EXPECT_GT(sigma, 1e-6) << a;
    EXPECT_LT(sigma, 1e-3) << a;
  }
  EXPECT_FALSE(j.at("sigma").contains("time_offset_s"));  // not estimated without --time-offset
  EXPECT_LT(j.at("residual_after_m").get<double>(), j.at("residual_before_m").get<double>());
  // A steady circle cannot check the wheels against the gyro: it says so (and no more).
  ASSERT_EQ(j.at("warnings").size(), 1u) << j.at("warnings");
  EXPECT_NE(j.at("warnings")[0].get<std::string>().find("cannot check the wheels"),
            std::string::npos)
      << j.at("warnings");
  // The paper's method is reported beside ours.
  const nlohmann::json paper = j.at("paper");
  EXPECT_EQ(paper.at("method"), "paper_points");
  EXPECT_TRUE(paper.contains("gamma_rad") && paper.contains("residual_after_m"));

  // The file goes into a rig file through mounting.calibration_file (relative to the rig).
  const MountingCalibration c = loadMountingCalibration(out.string());
  EXPECT_NEAR(c.gamma_rad, j.at("gamma_rad").get<double>(), 1e-12);  // 12 digits in the file
  EXPECT_EQ(c.source.at("tool"), "sweepmap calib mounting");
  std::string rig = readFile(kRigB);
  const std::string from = "  calibration_file: \"\"";  // mounting's, not the top-level one
  ASSERT_NE(rig.find(from), std::string::npos);
  rig.replace(rig.find(from), from.size(), "  calibration_file: mounting_calibration.yaml");
  std::ofstream(dir / "rig_b.yaml") << rig;
  const MobileLidarConfig loaded = loadMobileLidarConfig((dir / "rig_b.yaml").string());
  EXPECT_DOUBLE_EQ(loaded.mounting.gamma_rad, c.gamma_rad);
  EXPECT_DOUBLE_EQ(loaded.mounting.beta_rad, c.beta_rad);
  EXPECT_DOUBLE_EQ(loaded.mounting.alpha_rad, c.alpha_rad);
  EXPECT_DOUBLE_EQ(loaded.mounting.toMounting().alpha_rad, c.alpha_rad);
}

TEST(CalibCli, MountingBadInputsFailClearly) {
  const fs::path dir = scratchDir("calib_cli_mounting_bad");
  const fs::path out = dir / "m.yaml";
  const auto run = [&](const std::vector<std::string>& args, const std::string& label) {
    std::vector<std::string> a = {"calib", "mounting"};
    a.insert(a.end(), args.begin(), args.end());
    return runSplit(a, dir / (label + ".out"), dir / (label + ".err"));
  };
  // Missing log (given by --log, the hidden alias of --logs).
  EXPECT_EQ(run({"--log", (dir / "nope.lcmlog").string(), "--rig", kRigB, "--out", out.string()},
                "missing"),
            2);
  EXPECT_NE(readFile(dir / "missing.err").find("nope.lcmlog"), std::string::npos);
  // Corrupt log: bytes that are no LCM log.
  std::ofstream(dir / "corrupt.lcmlog") << std::string(4096, 'x');
  EXPECT_NE(
      run({"--logs", (dir / "corrupt.lcmlog").string(), "--rig", kRigB, "--out", out.string()},
          "corrupt"),
      0);
  EXPECT_FALSE(readFile(dir / "corrupt.err").empty());
  // A bad rig key names the key.
  EXPECT_EQ(run({"--logs", (dir / "corrupt.lcmlog").string(), "--rig", kRigB, "--out", out.string(),
                 "--set", "mounting.gama_rad=1"},
                "badkey"),
            2);
  EXPECT_NE(readFile(dir / "badkey.err").find("mounting.gama_rad"), std::string::npos)
      << readFile(dir / "badkey.err");
  // A missing calibration file named by the rig.
  EXPECT_EQ(run({"--logs", (dir / "corrupt.lcmlog").string(), "--rig", kRigB, "--out", out.string(),
                 "--set", "mounting.calibration_file=absent.yaml"},
                "badcalib"),
            2);
  EXPECT_NE(readFile(dir / "badcalib.err").find("absent.yaml"), std::string::npos);
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
