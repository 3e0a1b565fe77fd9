// The live processes over LCM, in a private network namespace that this test creates:
// the clouds they publish equal those of the offline replay of their own log, and a
// `sweepmap sim` log played by lcm-logplayer gives the clouds `sweepmap replay` gives; for
// rig B, a `sweepmap sim --rig rig_b` log played into sweepmap-odometry, sweepmap-assembler
// and sweepmap-mapper (all --rig rig_b) gives the poses, clouds and map of `sweepmap replay`;
// rig C's demo (sweepmap-profiler, -assembler, -mapper) equals its replay.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <thread>

#include "processes/channels.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "tests/e2e/test_support.hpp"
#include "tools/ops/netns.hpp"
#include "tools/ops/process_group.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");
const std::string kUrl = kDefaultLcmUrl;

class LiveTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string why;
    netns_ok_ = enterPrivateNetwork(&why);
    netns_why_ = why;
  }
  void SetUp() override {
    if (!netns_ok_) GTEST_SKIP() << "no private network namespace: " << netns_why_;
  }
  static std::vector<std::string> proc(const std::string& name, std::vector<std::string> args) {
    args.insert(args.begin(), binPath("sweepmap-" + name));
    args.insert(args.end(), {"--rig", kRig, "--set", "motor.mode=1", "--lcm-url", kUrl});
    return args;
  }
  // Chunk payloads of SWEEP_CLOUD keyed by (sweep, chunk).
  static std::map<std::pair<int64_t, int>, std::vector<uint8_t>> chunks(const std::string& log) {
    std::map<std::pair<int64_t, int>, std::vector<uint8_t>> out;
    for (const auto& m : readChannel(log, channels::kSweepCloud)) {
      cloud_chunk_t c;
      EXPECT_TRUE(decodeMessage(m, &c));
      out[{c.sweep_id, c.chunk_index}] = m.data;
    }
    return out;
  }
  // A stage of a live pipeline: its pid, its log, how long it may take to stop.
  struct Stage {
    pid_t pid;
    fs::path log;
    double stop_s;
  };
  // Plays `log` into the running pipeline, lets it drain, then stops the stages upstream first
  // (each hands its last messages on before the next one stops), then the logger.
  static void playThenStop(ProcessGroup& procs, const fs::path& dir, const std::string& log,
                           double play_timeout_s, const std::vector<Stage>& stages, pid_t logger) {
    const pid_t player = procs.start("logplayer", {"lcm-logplayer", "--lcm-url=" + kUrl, log},
                                     (dir / "logplayer.txt").string());
    ASSERT_EQ(procs.wait(player, play_timeout_s), 0) << readFile(dir / "logplayer.txt");
    std::this_thread::sleep_for(std::chrono::milliseconds(800));
    for (const Stage& stage : stages) {
      EXPECT_EQ(procs.stop(stage.pid, stage.stop_s), 0) << readFile(stage.log);
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
    }
    EXPECT_EQ(procs.stop(logger, 10.0), 0);
  }
  static bool netns_ok_;
  static std::string netns_why_;
};

bool LiveTest::netns_ok_ = false;
std::string LiveTest::netns_why_;

TEST_F(LiveTest, LiveCloudsEqualOfflineReplayOfTheirLog) {
  const auto dir = scratchDir("live_vs_offline");
  const std::string log = (dir / "live.lcmlog").string();
  ProcessGroup procs;
  const pid_t logger = procs.start("logger", {"lcm-logger", "--lcm-url=" + kUrl, "-f", log},
                                   (dir / "logger.txt").string());
  const pid_t assembler =
      procs.start("assembler", proc("assembler", {}), (dir / "assembler.txt").string());
  const pid_t lidar =
      procs.start("lidar", proc("lidar", {"--sim", "--scene", kScene, "--seed", "3"}),
                  (dir / "lidar.txt").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  const pid_t motor = procs.start("motor", proc("motor", {"--sim", "--sweeps", "2", "--seed", "3"}),
                                  (dir / "motor.txt").string());
  ASSERT_EQ(procs.wait(motor, 90.0), 0) << readFile(dir / "motor.txt");
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  EXPECT_EQ(procs.stop(lidar, 5.0), 0);
  EXPECT_EQ(procs.stop(assembler, 10.0), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(procs.stop(logger, 10.0), 0);

  const auto live = chunks(log);
  ASSERT_FALSE(live.empty()) << "the live assembler published nothing";
  ASSERT_EQ(sweepmap({"replay", log, "--rig", kRig, "--set", "motor.mode=1", "--out",
                      (dir / "offline").string(), "--no-plots"},
                     dir / "replay.txt"),
            0)
      << readFile(dir / "replay.txt");
  const auto offline = chunks((dir / "offline" / "derived.lcmlog").string());
  EXPECT_EQ(live.size(), offline.size());
  int sweeps = 0;
  for (const auto& [key, bytes] : live) {
    ASSERT_TRUE(offline.count(key)) << "sweep " << key.first << " chunk " << key.second;
    EXPECT_TRUE(bytes == offline.at(key))
        << "sweep " << key.first << " chunk " << key.second << " differs between live and offline";
    sweeps += key.second == 0;
  }
  EXPECT_EQ(sweeps, 2);
}

TEST_F(LiveTest, LogplayerIntoLiveProcessesMatchesReplay) {
  const auto dir = scratchDir("logplayer");
  const std::string sim_log = (dir / "sim.lcmlog").string();
  ASSERT_EQ(sweepmap({"sim", "--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "2",
                      "--seed", "8", "--out", sim_log}),
            0);
  const std::string rec = (dir / "recorded.lcmlog").string();
  ProcessGroup procs;
  const pid_t logger = procs.start(
      "logger", {"lcm-logger", "--lcm-url=" + kUrl, "-f", "-c", "SWEEP_.*|MAP_STATS", rec},
      (dir / "logger.txt").string());
  const pid_t assembler =
      procs.start("assembler", proc("assembler", {}), (dir / "assembler.txt").string());
  const pid_t mapper =
      procs.start("mapper", proc("mapper", {"--save", (dir / "live_map.bt").string()}),
                  (dir / "mapper.txt").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  const pid_t player = procs.start("logplayer", {"lcm-logplayer", "--lcm-url=" + kUrl, sim_log},
                                   (dir / "logplayer.txt").string());
  ASSERT_EQ(procs.wait(player, 120.0), 0) << readFile(dir / "logplayer.txt");
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  EXPECT_EQ(procs.stop(assembler, 10.0), 0);
  EXPECT_EQ(procs.stop(mapper, 60.0), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(procs.stop(logger, 10.0), 0);
  EXPECT_TRUE(fs::exists(dir / "live_map.bt"));

  ASSERT_EQ(sweepmap({"replay", sim_log, "--rig", kRig, "--set", "motor.mode=1", "--out",
                      (dir / "offline").string(), "--no-plots"}),
            0);
  const auto live = chunks(rec);
  const auto offline = chunks((dir / "offline" / "derived.lcmlog").string());
  ASSERT_FALSE(live.empty());
  EXPECT_EQ(live.size(), offline.size());
  for (const auto& [key, bytes] : offline) {
    ASSERT_TRUE(live.count(key)) << "sweep " << key.first << " chunk " << key.second;
    EXPECT_TRUE(bytes == live.at(key));
  }
  // The live mapper's map equals the replayed one (same sweeps, same order).
  EXPECT_TRUE(readFile(dir / "live_map.bt") == readFile(dir / "offline" / "map.bt"));
}

TEST_F(LiveTest, RigBLogplayerIntoLiveProcessesMatchesReplayMobile) {
  const auto dir = scratchDir("live_rig_b");
  const std::string rig_b = sourcePath("config/rig_b.yaml");
  const std::string sim_log = (dir / "sim.lcmlog").string();
  ASSERT_EQ(sweepmap({"sim", "--rig", rig_b, "--scene", sourcePath("config/scene_lab.yaml"),
                      "--set", "sim.duration_s=12", "--seed", "5", "--out", sim_log}),
            0);
  const std::string rec = (dir / "recorded.lcmlog").string();
  const auto procB = [&](const std::string& name, std::vector<std::string> args) {
    args.insert(args.begin(), binPath("sweepmap-" + name));
    args.insert(args.end(), {"--rig", rig_b, "--lcm-url", kUrl});
    return args;
  };
  ProcessGroup procs;
  const pid_t logger = procs.start("logger",
                                   {"lcm-logger", "--lcm-url=" + kUrl, "-f", "-c",
                                    "ODOMETRY_POSE|WHEEL_ODOMETRY|SWEEP_CLOUD", rec},
                                   (dir / "logger.txt").string());
  const pid_t odometry =
      procs.start("odometry", procB("odometry", {"--from-lcm"}), (dir / "odometry.txt").string());
  const pid_t assembler =
      procs.start("assembler", procB("assembler", {}), (dir / "assembler.txt").string());
  const pid_t mapper =
      procs.start("mapper", procB("mapper", {"--save", (dir / "live_map.bt").string()}),
                  (dir / "mapper.txt").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  playThenStop(procs, dir, sim_log, 120.0,
               {{odometry, dir / "odometry.txt", 10.0},
                {assembler, dir / "assembler.txt", 10.0},
                {mapper, dir / "mapper.txt", 60.0}},
               logger);
  if (HasFatalFailure()) return;

  const auto offline_dir = dir / "offline";
  ASSERT_EQ(
      sweepmap({"replay", sim_log, "--rig", rig_b, "--out", offline_dir.string(), "--no-plots"},
               dir / "replay.txt"),
      0)
      << readFile(dir / "replay.txt");
  const std::string derived = (offline_dir / "derived.lcmlog").string();
  for (const char* channel :
       {channels::kOdometryPose, channels::kWheelOdometry, channels::kSweepCloud}) {
    const auto live = readChannel(rec, channel);
    const auto offline = readChannel(derived, channel);
    ASSERT_FALSE(offline.empty()) << channel;
    ASSERT_EQ(live.size(), offline.size()) << channel;
    size_t differ = 0;
    for (size_t i = 0; i < live.size(); ++i) differ += live[i].data != offline[i].data;
    EXPECT_EQ(differ, 0u) << channel << ": " << differ << " of " << live.size()
                          << " messages differ between live and offline";
  }
  EXPECT_TRUE(readFile(dir / "live_map.bt") == readFile(offline_dir / "map.bt"))
      << "the live mapper's map differs from the replay's";
}

// `sweepmap demo` for a mobile_lidar rig: sweepmap-lidar and sweepmap-odometry drive one
// simulated car into the assembler and mapper; the live mapper's map equals the replay of the
// recorded log, byte for byte.
TEST_F(LiveTest, RigBDemoLiveMapEqualsReplayedMap) {
  const auto dir = scratchDir("demo_rig_b");
  ASSERT_EQ(sweepmap({"demo", "--rig", "rig_b", "--set", "sim.duration_s=8", "--seed", "3", "--out",
                      dir.string()},
                     dir / "demo.txt"),
            0)
      << readFile(dir / "demo.txt");
  for (const char* f :
       {"demo.lcmlog", "cloud.pcd", "map.bt", "live_map.bt", "summary.json", "top_view.png"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  }
  EXPECT_GT(readJson(dir / "summary.json")["scans"].get<int>(), 40);
  EXPECT_TRUE(readFile(dir / "live_map.bt") == readFile(dir / "map.bt"))
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
  const auto procC = [&](const std::string& name, std::vector<std::string> args) {
    args.insert(args.begin(), binPath("sweepmap-" + name));
    args.insert(args.end(), {"--rig", "rig_c", "--lcm-url", kUrl});
    return args;
  };
  ProcessGroup procs;
  const pid_t logger =
      procs.start("logger", {"lcm-logger", "--lcm-url=" + kUrl, "-f", "-c", "SWEEP_CLOUD", rec},
                  (dir / "logger.txt").string());
  const pid_t assembler =
      procs.start("assembler", procC("assembler", {}), (dir / "assembler.txt").string());
  const pid_t mapper =
      procs.start("mapper", procC("mapper", {"--save", (dir / "live_map.bt").string()}),
                  (dir / "mapper.txt").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  playThenStop(procs, dir, sim_log, 60.0,
               {{assembler, dir / "assembler.txt", 10.0}, {mapper, dir / "mapper.txt", 60.0}},
               logger);
  if (HasFatalFailure()) return;

  const auto offline_dir = dir / "offline";
  ASSERT_EQ(
      sweepmap({"replay", sim_log, "--rig", "rig_c", "--out", offline_dir.string(), "--no-plots"},
               dir / "replay.txt"),
      0)
      << readFile(dir / "replay.txt");
  const auto live = readChannel(rec, channels::kSweepCloud);
  const auto offline =
      readChannel((offline_dir / "derived.lcmlog").string(), channels::kSweepCloud);
  ASSERT_GT(offline.size(), 300u);
  ASSERT_EQ(live.size(), offline.size());
  size_t differ = 0;
  for (size_t i = 0; i < live.size(); ++i) differ += live[i].data != offline[i].data;
  EXPECT_EQ(differ, 0u) << differ << " of " << live.size() << " chunks differ";
  EXPECT_TRUE(readFile(dir / "live_map.bt") == readFile(offline_dir / "map.bt"))
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
                     dir / "demo.txt"),
            2);
  EXPECT_NE(readFile(dir / "demo.txt").find("only simulated devices"), std::string::npos);
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
                     dir / "demo.txt"),
            0)
      << readFile(dir / "demo.txt");
  for (const char* f :
       {"demo.lcmlog", "cloud.pcd", "map.bt", "live_map.bt", "summary.json", "top_view.png"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  }
  const std::string log = (dir / "demo.lcmlog").string();
  // Every profile the profiler published reached the log (its own count, in its last status).
  const auto profiles = readChannel(log, channels::kProfile);
  const auto statuses = readChannel(log, "STATUS_PROFILER");
  ASSERT_FALSE(statuses.empty());
  process_status_t last;
  ASSERT_TRUE(decodeMessage(statuses.back(), &last));
  int64_t published = -1;
  for (int i = 0; i < last.ncounters; ++i) {
    if (last.counter_names[i] == "profiles") published = last.counter_values[i];
  }
  EXPECT_EQ(published, static_cast<int64_t>(profiles.size()));
  EXPECT_NEAR(static_cast<double>(profiles.size()), 3 * 426, 12);
  // The live assembler's chunks are the replay's, in the same order.
  const auto live = readChannel(log, channels::kSweepCloud);
  const auto offline = readChannel((dir / "derived.lcmlog").string(), channels::kSweepCloud);
  ASSERT_FALSE(offline.empty());
  ASSERT_EQ(live.size(), offline.size());
  size_t differ = 0;
  for (size_t i = 0; i < live.size(); ++i) differ += live[i].data != offline[i].data;
  EXPECT_EQ(differ, 0u) << differ << " of " << live.size() << " chunks differ";
  EXPECT_TRUE(readFile(dir / "live_map.bt") == readFile(dir / "map.bt"))
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
