// End to end through `sweepmap sim` and `sweepmap replay`: accuracy of the plate
// correction against the simulator's ground truth, determinism, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "core/event_log.hpp"
#include "core/set_arguments.hpp"
#include "sweepmap/truth_sweep_t.hpp"
#include "tests/e2e/test_support.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");

std::vector<std::string> simArgs(int mode, int sweeps, int seed,
                                 const std::vector<std::string>& sets = {}) {
  std::vector<std::string> a = {"--rig",    kRig,
                                "--scene",  kScene,
                                "--mode",   std::to_string(mode),
                                "--sweeps", std::to_string(sweeps),
                                "--seed",   std::to_string(seed)};
  appendSetArguments(&a, sets);
  const auto paper = paperModelArgs();  // the paper's error model
  a.insert(a.end(), paper.begin(), paper.end());
  return a;
}

// The plate's installation error is set to zero here (issue: "with the plate's
// installation error set to zero"), so phi_error measures the correction alone.
const std::vector<std::string> kNoInstallError = {"sim.alpha_true_deg=30"};
// Coarse map: these tests look at the sweeps, not at the map.
const std::vector<std::string> kFastReplay = {"--rig", kRig, "--no-plots", "--set",
                                              "mapper.resolution_m=0.2"};

void expectPhiErrorWithin(const nlohmann::json& summary, int sweeps, double bound_deg) {
  ASSERT_EQ(summary["sweeps"].size(), static_cast<size_t>(sweeps));
  double worst = 0.0;
  for (const auto& s : summary["sweeps"]) {
    ASSERT_TRUE(s["corrected"].get<bool>()) << s.dump();
    ASSERT_TRUE(s.contains("phi_error_deg")) << "no ground truth in the log";
    worst = std::max(worst, std::abs(s["phi_error_deg"].get<double>()));
    EXPECT_LE(std::abs(s["phi_error_deg"].get<double>()), bound_deg) << s.dump();
  }
  ::testing::Test::RecordProperty("worst_abs_phi_error_deg", std::to_string(worst));
  std::cout << "worst |phi_error| = " << worst << " deg over " << sweeps << " sweeps\n";
}

TEST(Accuracy, Mode7CorrectedWithin0p3Deg) {
  const std::string log = cachedSimLog("mode7x5", simArgs(7, 5, 11, kNoInstallError));
  const auto out = cachedReplay("mode7x5_replay", log, kFastReplay);
  expectPhiErrorWithin(readJson(out / "summary.json"), 5, 0.3);
}

TEST(Accuracy, Mode1CorrectedWithin1p5Deg) {
  const std::string log = cachedSimLog("mode1x5", simArgs(1, 5, 12, kNoInstallError));
  const auto out = cachedReplay("mode1x5_replay", log, kFastReplay);
  expectPhiErrorWithin(readJson(out / "summary.json"), 5, 1.5);
}

// Without the correction the clouds keep the attitude error the simulator injected:
// phi_error = -phi_true, and the injected errors are not all negligible.
TEST(Accuracy, UncorrectedShowsInjectedError) {
  for (int mode : {1, 7}) {
    const std::string log = cachedSimLog("mode" + std::to_string(mode) + "x5",
                                         simArgs(mode, 5, mode == 7 ? 11 : 12, kNoInstallError));
    auto args = kFastReplay;
    args.insert(args.end(), {"--set", "assembler.correct_attitude=false"});
    const auto out = cachedReplay("mode" + std::to_string(mode) + "x5_uncorrected", log, args);
    const auto summary = readJson(out / "summary.json");
    ASSERT_EQ(summary["sweeps"].size(), 5u);
    double worst = 0.0;
    for (const auto& s : summary["sweeps"]) {
      EXPECT_FALSE(s["corrected"].get<bool>());
      EXPECT_NEAR(s["phi_error_deg"].get<double>(), -s["phi_true_deg"].get<double>(), 1e-6);
      worst = std::max(worst, std::abs(s["phi_error_deg"].get<double>()));
    }
    std::cout << "mode " << mode << ": worst uncorrected |phi_error| = " << worst << " deg\n";
    EXPECT_GT(worst, mode == 1 ? 1.5 : 0.3) << "the simulator injected no visible error";
  }
}

TEST(Determinism, SimTwiceIsByteIdentical) {
  const auto dir = scratchDir("sim_twice");
  for (const char* name : {"a.lcmlog", "b.lcmlog"}) {
    auto args = simArgs(1, 2, 5);
    args.insert(args.begin(), "sim");
    args.insert(args.end(), {"--out", (dir / name).string()});
    ASSERT_EQ(sweepmap(args, dir / (std::string(name) + ".txt")), 0);
  }
  const std::string a = readFile(dir / "a.lcmlog");
  EXPECT_GT(a.size(), 100000u);
  EXPECT_TRUE(a == readFile(dir / "b.lcmlog")) << "sim logs differ";
  // A different seed gives a different log.
  auto args = simArgs(1, 2, 6);
  args.insert(args.begin(), "sim");
  args.insert(args.end(), {"--out", (dir / "c.lcmlog").string()});
  ASSERT_EQ(sweepmap(args), 0);
  EXPECT_FALSE(a == readFile(dir / "c.lcmlog"));
}

TEST(Determinism, ReplayTwiceIsByteIdentical) {
  const std::string log = cachedSimLog("mode1x2", simArgs(1, 2, 21));
  const auto dir = scratchDir("replay_twice");
  for (const char* name : {"a", "b"}) {
    ASSERT_EQ(sweepmap({"replay", log, "--rig", kRig, "--out", (dir / name).string()}), 0);
  }
  std::vector<std::string> files = {"map.bt", "summary.json", "derived.lcmlog"};
  for (const auto& e : fs::directory_iterator(dir / "a" / "sweeps")) {
    files.push_back("sweeps/" + e.path().filename().string());
  }
  EXPECT_EQ(files.size(), 3u + 4u);  // 2 sweeps x (PCD + PLY)
  for (const auto& f : files) {
    const std::string a = readFile(dir / "a" / f);
    EXPECT_FALSE(a.empty()) << f;
    EXPECT_TRUE(a == readFile(dir / "b" / f)) << f << " differs between two replays";
  }
  EXPECT_TRUE(fs::exists(dir / "a" / "top_view.png"));
  const auto summary = readJson(dir / "a" / "summary.json");
  EXPECT_GT(summary["map"]["occupied_voxels"].get<int64_t>(), 1000);
  EXPECT_EQ(summary["map"]["resolution_m"].get<double>(), 0.05);
  for (const auto& s : summary["sweeps"]) {
    for (const char* key :
         {"id", "mode", "points", "plate_points", "phi_offset_deg", "corrected", "phi_error_deg"}) {
      EXPECT_TRUE(s.contains(key)) << key;
    }
  }
}

// TRUTH_SWEEP carries the true phi_offset of each sweep; replay derives the same value
// from TRUTH_SHAFT at the window's first ray.
TEST(Truth, SweepTruthAgreesWithShaftTruth) {
  const std::string log = cachedSimLog("mode1x2", simArgs(1, 2, 21));
  const auto out = cachedReplay("mode1x2_replay", log, kFastReplay);
  const auto summary = readJson(out / "summary.json");
  const auto truths = readChannel(log, "TRUTH_SWEEP");
  ASSERT_EQ(truths.size(), 2u);
  for (size_t i = 0; i < truths.size(); ++i) {
    truth_sweep_t t{};
    ASSERT_TRUE(decodeMessage(truths[i], &t));
    EXPECT_EQ(t.sweep_id, static_cast<int64_t>(i));
    EXPECT_NEAR(t.phi_offset_true_rad * 180.0 / M_PI,
                summary["sweeps"][i]["phi_true_deg"].get<double>(), 1e-5);
    EXPECT_NEAR(t.alpha_true_rad * 180.0 / M_PI, 29.3598, 1e-9);
  }
}

TEST(BadInput, TruncatedLogKeepsOutputsAndNamesOffset) {
  const std::string log = cachedSimLog("mode1x2", simArgs(1, 2, 21));
  const auto dir = scratchDir("truncated");
  // Cut inside the last quarter: the first sweep is complete before the cut.
  const auto size = fs::file_size(log);
  const std::string bytes = readFile(log);
  {
    std::ofstream f(dir / "cut.lcmlog", std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(size * 3 / 4 + 7));
  }
  ASSERT_EQ(sweepmap({"replay", (dir / "cut.lcmlog").string(), "--rig", kRig, "--out",
                      (dir / "out").string()},
                     dir / "replay.txt"),
            1);
  const std::string err = readFile(dir / "replay.txt");
  EXPECT_NE(err.find("byte "), std::string::npos) << err;
  EXPECT_NE(err.find("truncated"), std::string::npos) << err;
  const auto summary = readJson(dir / "out" / "summary.json");
  EXPECT_TRUE(summary.contains("error"));
  EXPECT_GE(summary["sweeps"].size(), 1u);
  EXPECT_TRUE(fs::exists(dir / "out" / "sweeps" / "sweep_000000.pcd"));
  EXPECT_TRUE(fs::exists(dir / "out" / "map.bt"));
}

TEST(BadInput, CorruptLogNamesOffset) {
  const std::string log = cachedSimLog("mode1x2", simArgs(1, 2, 21));
  const auto dir = scratchDir("corrupt");
  std::string bytes = readFile(log);
  // Find the start of an event in the middle and break its sync word.
  EventLogReader r(log);
  LogEvent e;
  uint64_t offset = 0;
  while (r.offset() < bytes.size() / 2 && r.next(&e)) offset = r.offset();
  bytes[offset] = 0;
  std::ofstream(dir / "bad.lcmlog", std::ios::binary) << bytes;
  ASSERT_EQ(sweepmap({"replay", (dir / "bad.lcmlog").string(), "--rig", kRig, "--out",
                      (dir / "out").string(), "--no-plots"},
                     dir / "replay.txt"),
            1);
  EXPECT_NE(readFile(dir / "replay.txt").find("byte " + std::to_string(offset)), std::string::npos)
      << readFile(dir / "replay.txt");
  // Everything after the broken event is replayed: both sweeps are there, and every event but
  // the broken one.
  const auto summary = readJson(dir / "out" / "summary.json");
  EXPECT_EQ(summary["sweeps"].size(), 2u);
  int64_t events = 0;
  for (EventLogReader all(log); all.next(&e);) ++events;
  EXPECT_EQ(summary["events"].get<int64_t>(), events - 1);
  EXPECT_NE(summary["error"].get<std::string>().find("skipped: bad sync word"), std::string::npos);
}

TEST(BadInput, ConfigWithUnknownOrMissingKeyRejected) {
  const auto dir = scratchDir("badconfig");
  std::string rig = readFile(kRig);
  std::ofstream(dir / "unknown.yaml") << rig << "extra_key: 1\n";
  const std::string pos =
      rig.find("  beam_count: 1081\n") != std::string::npos ? "  beam_count: 1081\n" : "";
  ASSERT_FALSE(pos.empty());
  std::string missing = rig;
  missing.erase(missing.find(pos), pos.size());
  std::ofstream(dir / "missing.yaml") << missing;
  for (const auto& [file, key] : std::vector<std::pair<std::string, std::string>>{
           {"unknown.yaml", "extra_key"}, {"missing.yaml", "lidar.beam_count"}}) {
    const int rc = sweepmap({"sim", "--rig", (dir / file).string(), "--scene", kScene, "--out",
                             (dir / "x.lcmlog").string()},
                            dir / "out.txt");
    EXPECT_EQ(rc, 2);
    const std::string err = readFile(dir / "out.txt");
    EXPECT_NE(err.find(file), std::string::npos) << err;
    EXPECT_NE(err.find(key), std::string::npos) << err;
  }
  EXPECT_EQ(sweepmap({"sim", "--rig", kRig, "--scene", kScene, "--set", "motor.nope=1", "--out",
                      (dir / "x.lcmlog").string()},
                     dir / "out.txt"),
            2);
  EXPECT_NE(readFile(dir / "out.txt").find("motor.nope"), std::string::npos);
}

TEST(Interop, ReplaysLogWrittenByLcmTools) {
  const std::string log = std::string(SWEEPMAP_SHARED_DIR) + "/data/real/lcm_example.lcmlog";
  if (!fs::exists(log))
    GTEST_SKIP() << log << " not present (../shared is not beside this checkout)";
  const auto dir = scratchDir("lcm_example");
  // Read whole, its channels skipped: nothing made for a rig A, which is bad input (exit 1)
  // naming what the log holds; the summary is written all the same.
  ASSERT_EQ(
      sweepmap({"replay", log, "--rig", kRig, "--out", (dir / "out").string()}, dir / "replay.txt"),
      1)
      << readFile(dir / "replay.txt");
  EXPECT_NE(readFile(dir / "replay.txt").find("holds JOINT_TEST x10"), std::string::npos)
      << readFile(dir / "replay.txt");
  const auto summary = readJson(dir / "out" / "summary.json");
  EXPECT_EQ(summary["events"].get<int>(), 10);
  EXPECT_EQ(summary["skipped_channels"]["JOINT_TEST"].get<int>(), 10);
  EXPECT_TRUE(summary["sweeps"].empty());
}

TEST(Tool, PrintConfigListsEveryKeyWithUnits) {
  const auto dir = scratchDir("print_config");
  ASSERT_EQ(sweepmap({"sim", "--rig", kRig, "--scene", kScene, "--print-config"}, dir / "cfg.txt"),
            0);
  const std::string text = readFile(dir / "cfg.txt");
  for (const char* key :
       {"lidar.beam_count", "motor.mode", "plate.alpha_deg", "sim.range_noise_sigma_mm",
        "sim.alpha_true_deg", "mapper.resolution_m", "scene.room.length_m", "scene.rig.yaw_deg"}) {
    EXPECT_NE(text.find(key), std::string::npos) << key;
  }
  EXPECT_NE(text.find("[mm]"), std::string::npos);
}

TEST(Tool, SpyPutsTheTypesJarOnItsClassPath) {
  const auto dir = scratchDir("spy");
  ASSERT_EQ(sweepmap({"spy", "--print-command"}, dir / "cmd.txt"), 0) << readFile(dir / "cmd.txt");
  const std::string cmd = readFile(dir / "cmd.txt");
  EXPECT_NE(cmd.find("sweepmap_lcmtypes.jar"), std::string::npos) << cmd;
  EXPECT_NE(cmd.find("lcm.spy.Spy"), std::string::npos) << cmd;
  EXPECT_EQ(cmd.find("Xincgc"), std::string::npos) << cmd;
  // Its message view (double-clicking a channel) charts with jchart2d: every class it needs
  // loads from that class path (Debian's liblcm-java does not pull jchart2d in).
  const size_t cp_at = cmd.find("-cp ");
  ASSERT_NE(cp_at, std::string::npos) << cmd;
  const std::string cp = cmd.substr(cp_at + 4, cmd.find(' ', cp_at + 4) - cp_at - 4);
  std::ofstream(dir / "Check.java")
      << "public class Check { public static void main(String[] a) "
         "throws Exception { for (String c : a) Class.forName(c); } }";
  const std::string java =
      "java -Djava.awt.headless=true -cp " + cp + " " + (dir / "Check.java").string() +
      " lcm.spy.ChartData info.monitorenter.gui.chart.Chart2D "
      "info.monitorenter.gui.chart.traces.Trace2DLtd sweepmap.lidar_scan_t > " +
      (dir / "java.txt").string() + " 2>&1";
  EXPECT_EQ(std::system(java.c_str()), 0) << readFile(dir / "java.txt");
}

// Every rig kind through the same commands, by rig name, from a directory with no config/
// folder: the rig and scene files are found in the install tree (bin/../share/sweepmap).
TEST(Tool, SimAndReplayAnyRigByNameFromAnotherDirectory) {
  const auto dir = scratchDir("rig_names");
  ASSERT_EQ(sweepmapIn(
                dir, {"sim", "--rig", "rig_a", "--mode", "1", "--sweeps", "1", "--out", "a.lcmlog"},
                dir / "sim_a.txt"),
            0)
      << readFile(dir / "sim_a.txt");
  EXPECT_NE(readFile(dir / "sim_a.txt").find("rotating_lidar"), std::string::npos);
  ASSERT_EQ(sweepmapIn(dir, {"replay", "a.lcmlog", "--rig", "rig_a", "--no-plots", "--out", "a"},
                       dir / "replay_a.txt"),
            0)
      << readFile(dir / "replay_a.txt");
  EXPECT_EQ(readJson(dir / "a" / "summary.json")["sweeps"].size(), 1u);

  ASSERT_EQ(
      sweepmapIn(dir, {"sim", "--rig", "rig_b", "--set", "sim.duration_s=4", "--out", "b.lcmlog"},
                 dir / "sim_b.txt"),
      0)
      << readFile(dir / "sim_b.txt");
  EXPECT_NE(readFile(dir / "sim_b.txt").find("mobile_lidar"), std::string::npos);
  ASSERT_EQ(
      sweepmapIn(dir, {"replay", "b.lcmlog", "--rig", "mobile_lidar", "--no-plots", "--out", "b"},
                 dir / "replay_b.txt"),
      0)
      << readFile(dir / "replay_b.txt");
  EXPECT_GT(readJson(dir / "b" / "summary.json")["scans"].get<int>(), 0);
}

// A rig of the wrong kind for a command, a file without a kind, a name that is nowhere:
// each a config error (exit 2) that names the file and what was expected.
TEST(Tool, RigKindErrorsAreClear) {
  const auto dir = scratchDir("rig_kind_errors");
  std::ofstream(dir / "x.lcmlog").close();  // a log that exists: the rig is what is wrong
  EXPECT_EQ(sweepmap({"sim", "--rig", "rig_b", "--mode", "3", "--out", (dir / "x.lcmlog").string()},
                     dir / "mode.txt"),
            2);
  EXPECT_NE(readFile(dir / "mode.txt").find("rotating_lidar"), std::string::npos)
      << readFile(dir / "mode.txt");
  EXPECT_EQ(sweepmap({"calib", "mounting", "--logs", (dir / "x.lcmlog").string(), "--rig", "rig_a",
                      "--out", (dir / "m.yaml").string()},
                     dir / "calib.txt"),
            2);
  EXPECT_NE(readFile(dir / "calib.txt").find("needs a mobile_lidar rig"), std::string::npos)
      << readFile(dir / "calib.txt");
  std::ofstream(dir / "nokind.yaml") << "lidar:\n  beam_count: 10\n";
  EXPECT_EQ(sweepmap({"replay", (dir / "x.lcmlog").string(), "--rig",
                      (dir / "nokind.yaml").string(), "--out", (dir / "o").string()},
                     dir / "nokind.txt"),
            2);
  EXPECT_NE(readFile(dir / "nokind.txt").find("missing key 'rig'"), std::string::npos)
      << readFile(dir / "nokind.txt");
  EXPECT_EQ(sweepmap({"replay", (dir / "x.lcmlog").string(), "--rig", "rig_z", "--out",
                      (dir / "o").string()},
                     dir / "noname.txt"),
            2);
  EXPECT_NE(readFile(dir / "noname.txt").find("rig_z.yaml"), std::string::npos)
      << readFile(dir / "noname.txt");
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
