// The live processes over LCM, in a private network namespace that this test creates:
// the clouds they publish equal those of the offline replay of their own log, and a
// `sweepmap sim` log played by lcm-logplayer gives the clouds `sweepmap replay` gives; for
// rig B, a `sweepmap sim --rig rig_b` log played into sweepmap-odometry, sweepmap-assembler
// and sweepmap-mapper (all --rig rig_b) gives the poses, clouds and map of `sweepmap replay`;
// rig C's demo (sweepmap-profiler, -assembler, -mapper) equals its replay.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>

#include "processes/channels.hpp"
#include "tests/e2e/fixtures.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");
const std::string kUrl = kDefaultLcmUrl;

class LiveTest : public PrivateNetworkTest {
 protected:
  // Rig A's processes in mode 1.
  const ProcessCommand proc{{"--rig", kRig, "--set", "motor.mode=1", "--lcm-url", kUrl}};
  Launcher procs;

  // Plays `log` into the `upstream` processes (name, arguments), sweepmap-assembler and
  // sweepmap-mapper (its map in DIR/live_map.bt), all made by `command`, with lcm-logger
  // recording `channels` into DIR/recorded.lcmlog; then stops them upstream first, the logger
  // last.
  using Stages = std::vector<std::pair<std::string, std::vector<std::string>>>;
  void playIntoLive(const fs::path& dir, const ProcessCommand& command, const std::string& log,
                    double timeout_s, const std::string& channels, const Stages& upstream = {}) {
    procs.setDir(dir);
    const pid_t logger = procs.startSubscriber(
        "logger", loggerCommand(kUrl, (dir / "recorded.lcmlog").string(), channels),
        kDefaultLcmPort);
    std::vector<Stop> stops;
    for (const auto& [name, args] : upstream) {
      stops.push_back({procs.startSubscriber(name, command(name, args), kDefaultLcmPort), 10.0});
    }
    stops.push_back(
        {procs.startSubscriber("assembler", command("assembler"), kDefaultLcmPort), 10.0});
    stops.push_back({procs.startSubscriber(
                         "mapper", command("mapper", {"--save", (dir / "live_map.bt").string()}),
                         kDefaultLcmPort),
                     60.0});
    stops.push_back({logger, 10.0});
    ASSERT_EQ(procs.play(kUrl, log, timeout_s), 0) << procs.said("logplayer");
    procs.stopInOrder(stops, 0.8);
  }
};

// What `sweepmap demo` leaves in its --out folder.
void expectDemoOutputs(const fs::path& dir) {
  for (const char* f :
       {"demo.lcmlog", "cloud.pcd", "map.bt", "live_map.bt", "summary.json", "top_view.png"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  }
}

TEST_F(LiveTest, LiveCloudsEqualOfflineReplayOfTheirLog) {
  const auto dir = scratchDir("live_vs_offline");
  procs.setDir(dir);
  const std::string log = (dir / "live.lcmlog").string();
  const pid_t logger = procs.startSubscriber("logger", loggerCommand(kUrl, log), kDefaultLcmPort);
  const pid_t assembler = procs.startSubscriber("assembler", proc("assembler"), kDefaultLcmPort);
  const pid_t lidar = procs.startSubscriber(
      "lidar", proc("lidar", {"--sim", "--scene", kScene, "--seed", "3"}), kDefaultLcmPort);
  const pid_t motor =
      procs.start("motor", proc("motor", {"--sim", "--sweeps", "2", "--seed", "3"}));
  ASSERT_EQ(procs.wait(motor, 90.0), 0) << procs.said(motor);
  procs.stopInOrder({{lidar, 5.0}, {assembler, 10.0}, {logger, 10.0}}, 0.8);

  const Chunks live = chunksOf(log);
  ASSERT_FALSE(live.empty()) << "the live assembler published nothing";
  ASSERT_EQ(replayInto(dir / "offline", log, {"--rig", kRig, "--set", "motor.mode=1"}), 0)
      << readFile(dir / "replay.txt");
  ASSERT_TRUE(sameChunks(live, chunksOf((dir / "offline" / "derived.lcmlog").string())));
  int sweeps = 0;
  for (const auto& [key, bytes] : live) sweeps += key.second == 0;
  EXPECT_EQ(sweeps, 2);
}

TEST_F(LiveTest, LogplayerIntoLiveProcessesMatchesReplay) {
  const auto dir = scratchDir("logplayer");
  const std::string sim_log = (dir / "sim.lcmlog").string();
  ASSERT_EQ(sweepmap({"sim", "--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "2",
                      "--seed", "8", "--out", sim_log}),
            0);
  const std::string rec = (dir / "recorded.lcmlog").string();
  ASSERT_NO_FATAL_FAILURE(playIntoLive(dir, proc, sim_log, 120.0, "SWEEP_.*|MAP_STATS"));
  EXPECT_TRUE(fs::exists(dir / "live_map.bt"));

  ASSERT_EQ(replayInto(dir / "offline", sim_log, {"--rig", kRig, "--set", "motor.mode=1"}), 0)
      << readFile(dir / "replay.txt");
  const Chunks live = chunksOf(rec);
  ASSERT_FALSE(live.empty());
  ASSERT_TRUE(sameChunks(live, chunksOf((dir / "offline" / "derived.lcmlog").string())));
  // The live mapper's map equals the replayed one (same sweeps, same order).
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", dir / "offline" / "map.bt"));
}

TEST_F(LiveTest, RigBLogplayerIntoLiveProcessesMatchesReplayMobile) {
  const auto dir = scratchDir("live_rig_b");
  const std::string rig_b = sourcePath("config/rig_b.yaml");
  const std::string sim_log = (dir / "sim.lcmlog").string();
  ASSERT_EQ(sweepmap({"sim", "--rig", rig_b, "--scene", sourcePath("config/scene_lab.yaml"),
                      "--set", "sim.duration_s=12", "--seed", "5", "--out", sim_log}),
            0);
  const std::string rec = (dir / "recorded.lcmlog").string();
  ASSERT_NO_FATAL_FAILURE(playIntoLive(dir, ProcessCommand({"--rig", rig_b, "--lcm-url", kUrl}),
                                       sim_log, 120.0, "ODOMETRY_POSE|WHEEL_ODOMETRY|SWEEP_CLOUD",
                                       {{"odometry", {"--from-lcm"}}}));

  const auto offline_dir = dir / "offline";
  ASSERT_EQ(replayInto(offline_dir, sim_log, {"--rig", rig_b}), 0) << readFile(dir / "replay.txt");
  const std::string derived = (offline_dir / "derived.lcmlog").string();
  for (const char* channel :
       {channels::kOdometryPose, channels::kWheelOdometry, channels::kSweepCloud}) {
    ASSERT_TRUE(sameMessages(rec, derived, channel));
  }
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", offline_dir / "map.bt"))
      << "the live mapper's map differs from the replay's";
}

// `sweepmap demo` for a mobile_lidar rig: sweepmap-lidar and sweepmap-odometry drive one
// simulated car into the assembler and mapper; the live mapper's map equals the replay of the
// recorded log, byte for byte.
TEST_F(LiveTest, RigBDemoLiveMapEqualsReplayedMap) {
  const auto dir = scratchDir("demo_rig_b");
  ASSERT_EQ(sweepmap({"demo", "--rig", "rig_b", "--set", "sim.duration_s=8", "--seed", "3", "--out",
                      dir.string()},
                     fs::path(dir.string() + ".demo.txt")),
            0)
      << readFile(fs::path(dir.string() + ".demo.txt"));
  expectDemoOutputs(dir);
  EXPECT_GT(readJson(dir / "summary.json")["scans"].get<int>(), 40);
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", dir / "map.bt"))
      << "the live mapper's map differs from the replay of the recorded log";
}

// A `sweepmap sim --rig rig_c` log (the test piece) played by lcm-logplayer into
// sweepmap-assembler and sweepmap-mapper (--rig rig_c) gives the chunks and map of `sweepmap
// replay`: the offline simulation's raw messages are what the live processes take.
TEST_F(LiveTest, RigCLogplayerIntoLiveProcessesMatchesReplay) {
  const auto dir = scratchDir("live_rig_c");
  const std::string sim_log = (dir / "sim.lcmlog").string();
  ASSERT_EQ(
      sweepmap({"sim", "--rig", "rig_c", "--scene", "test_piece", "--seed", "6", "--out", sim_log}),
      0);
  const std::string rec = (dir / "recorded.lcmlog").string();
  ASSERT_NO_FATAL_FAILURE(playIntoLive(dir, ProcessCommand({"--rig", "rig_c", "--lcm-url", kUrl}),
                                       sim_log, 60.0, "SWEEP_CLOUD"));

  const auto offline_dir = dir / "offline";
  ASSERT_EQ(replayInto(offline_dir, sim_log, {"--rig", "rig_c"}), 0)
      << readFile(dir / "replay.txt");
  ASSERT_TRUE(
      sameMessages(rec, (offline_dir / "derived.lcmlog").string(), channels::kSweepCloud, 300));
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", offline_dir / "map.bt"))
      << "the live mapper's map differs from the replay's";
}

// sweepmap-profiler refuses what it cannot serve before opening anything: another kind's rig,
// a device with no driver, bad flags (exit 2, naming the reason).
TEST(RigCProcesses, ProfilerRefusesOtherKindsAndDevicesItHasNoDriverFor) {
  const auto dir = scratchDir("profiler_refuses");
  const auto run = [&](const std::string& args, const std::string& name) {
    const std::string out = (dir / (name + ".txt")).string();
    const int rc =
        std::system((binPath("sweepmap-profiler") + " " + args + " > " + out + " 2>&1").c_str());
    return std::make_pair(WEXITSTATUS(rc), readFile(out));
  };
  const auto [kind_rc, kind] = run("--rig rig_a", "kind");
  EXPECT_EQ(kind_rc, 2);
  EXPECT_NE(kind.find("needs a rotating_profile rig"), std::string::npos) << kind;
  const auto [device_rc, device] =
      run("--rig rig_c --set turntable.device=serial:///dev/x", "device");
  EXPECT_EQ(device_rc, 2);
  EXPECT_NE(device.find("turntable.device"), std::string::npos) << device;
  const auto [flag_rc, flag] = run("--rig rig_c --pause-s -1", "flag");
  EXPECT_NE(flag_rc, 0);
  // The demo has no emulated devices for rig C.
  EXPECT_EQ(sweepmap({"demo", "--rig", "rig_c", "--devices", "emulated", "--out",
                      (dir / "demo").string()},
                     fs::path(dir.string() + ".demo.txt")),
            2);
  EXPECT_NE(readFile(fs::path(dir.string() + ".demo.txt")).find("only simulated devices"),
            std::string::npos);
}

// Rig C live: `sweepmap demo --rig rig_c` runs sweepmap-profiler (the simulated turntable and
// profile sensor), -assembler and -mapper in the private network: the live clouds and map
// equal the replay of the recorded log byte for byte, nothing was lost on the way, and with
// the true geometry every plate pose's points lie on its true plane.
TEST_F(LiveTest, RigCDemoLiveEqualsReplayAndThePlatesAreFlat) {
  const auto dir = scratchDir("demo_rig_c");
  ASSERT_EQ(sweepmap({"demo", "--rig", "rig_c", "--seed", "2", "--set", "geometry.offset_m_mm=123",
                      "--set", "geometry.offset_n_mm=409", "--set", "geometry.laser_tilt_deg=0.2",
                      "--set", "geometry.encoder_zero_deg=0.5", "--out", dir.string()},
                     fs::path(dir.string() + ".demo.txt")),
            0)
      << readFile(fs::path(dir.string() + ".demo.txt"));
  expectDemoOutputs(dir);
  const std::string log = (dir / "demo.lcmlog").string();
  // Every profile the profiler published reached the log (its own count, in its last status).
  const auto profiles = readChannel(log, channels::kProfile);
  const LastStatus last = lastStatus(log, "STATUS_PROFILER");
  ASSERT_TRUE(last.found);
  EXPECT_EQ(last.counter("profiles", -1), static_cast<int64_t>(profiles.size()));
  EXPECT_NEAR(static_cast<double>(profiles.size()), 3 * 426, 12);
  // The live assembler's chunks are the replay's, in the same order.
  ASSERT_TRUE(sameMessages(log, (dir / "derived.lcmlog").string(), channels::kSweepCloud));
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", dir / "map.bt"))
      << "the live mapper's map differs from the replay of the recorded log";
  const auto summary = readJson(dir / "summary.json");
  ASSERT_EQ(summary["sweeps"].size(), 3u);
  EXPECT_EQ(summary["invalid_profiles"].get<int>(), 0);
  for (int k = 0; k < 3; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "sweeps/sweep_%06d.pcd", k);
    const double rms = rmsToTruePlane(log, dir / name, k);
    std::printf("live sweep %d: RMS to the true plane %.4f mm\n", k, rms);
    EXPECT_GE(rms, 0.0) << "no truth for sweep " << k;
    EXPECT_LT(rms, 0.05) << k;  // range noise 0.02 mm, encoder quantisation and noise
  }
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
