// Hostile traffic on the robot's network (issue 21), in a private network namespace. Every
// finding of the issue is sent against every kind of process that listens, while it runs:
//  - datagrams that crash every liblcm 1.3.1 receiver (an LC03 fragment at offset 0xFFFFFFFF,
//    an LC02 whose channel has no NUL) and a flood of their mutations;
//  - messages whose string length is INT32_MIN (MAP_SAVE, SWEEP_STATUS, STATUS_*), STATUS_*
//    with 2^26 and 2^31-1 counters or a detail that is not UTF-8;
//  - raw messages stamped a day ahead (LIDAR_SCAN, IMU, WHEEL_TICKS, PROFILE), sent while the
//    good stream flows;
//  - MAP_SAVE requests for hostile names (outside the folder, not .bt, an existing file, a
//    newline, an option, a flood).
// One launch per rig kind takes all of them: rig A (assembler, mapper, `sweepmap record`,
// `sweepmap status`), rig B (odometry, world assembler, mapper, recorder) and rig C (profile
// assembler, mapper, recorder; the profiler on a port of its own). No process dies, every
// refusal is counted in the status, and the good traffic gives exactly what `sweepmap replay`
// gives from the same log without the attack. With a shared key, forged (unsigned) copies of
// the sensors' messages never reach a node; the units `sweepmap systemd` writes hear only the
// deployment's hosts and refuse a key file others may read.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "core/event_log.hpp"
#include "processes/channels.hpp"
#include "processes/node.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "tests/e2e/fixtures.hpp"
#include "tools/bench/hostile_traffic.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");
const std::string kUrl = kDefaultLcmUrl;
constexpr uint16_t kPort = kDefaultLcmPort;
constexpr int64_t kDayUs = 86'400'000'000;

using hostile::Bytes;

// Sends datagrams to LCM's group on `port` from a socket of their own, as another host on the
// LAN would.
void sendDatagrams(const std::vector<Bytes>& datagrams, uint16_t port = kPort) {
  const size_t sent = hostile::MulticastSender("239.255.76.67", port).send(datagrams);
  EXPECT_EQ(sent, datagrams.size()) << "DEBUG";
}

// The datagrams that crash liblcm 1.3.1 on each of `channels`, and `flood` mutations of them.
std::vector<Bytes> crashDatagrams(const std::vector<std::string>& channels, int flood) {
  return hostile::malformedDatagrams(channels, flood, 21);
}

// Messages whose decoding overflows in lcm-gen's code (a string length of INT32_MIN), status
// messages with absurd counter counts or a detail that is not UTF-8. Each is a well-formed
// datagram: only the message is hostile.
std::vector<Bytes> hostileMessages() {
  return hostile::datagramsOf(
      {{channels::kMapSave, hostile::mapSaveWithMinLength()},
       {channels::kSweepStatus, hostile::sweepStatusWithMinLength()},
       {"STATUS_INTRUDER", hostile::statusWithMinLength()},
       {"STATUS_INTRUDER", hostile::statusWithHugeCount("intruder", 1u << 26)},
       {"STATUS_INTRUDER", hostile::statusWithHugeCount("intruder", 0x7FFFFFFFu)},
       {"STATUS_INTRUDER", hostile::statusWithBadUtf8("intruder")}},
      1);
}

// MAP_SAVE requests a mapper must refuse (or honour at most once a second and for 16 names).
std::vector<Bytes> hostileSaves() {
  std::vector<Bytes> d;
  std::vector<std::string> names = {"../escape.bt", "/tmp/abs.bt", "-rf", "evil\nname.bt",
                                    "sim.lcmlog",   "notes.txt",   ".bt", std::string(300, 'a')};
  for (int i = 0; i < 30; ++i) names.push_back("flood" + std::to_string(i) + ".bt");
  std::vector<hostile::Forged> saves;
  for (const auto& name : names) saves.push_back({channels::kMapSave, hostile::mapSave(name, 1)});
  return hostile::datagramsOf(saves, 100);
}

// The first message of `channel` in `log`, stamped a day ahead.
Bytes dayAhead(const std::string& log, const std::string& channel) {
  EventLogReader reader(log);
  LogEvent e;
  while (reader.next(&e)) {
    if (e.channel != channel || e.data.size() < 16) continue;
    int64_t stamp = 0;
    for (size_t k = 8; k < 16; ++k) stamp = (stamp << 8) | e.data[k];
    stamp += kDayUs;
    for (size_t k = 0; k < 8; ++k) e.data[15 - k] = static_cast<uint8_t>(stamp >> (8 * k));
    return hostile::datagramsOf({{channel, e.data}}, 200).front();
  }
  ADD_FAILURE() << "no " << channel << " in " << log;
  return {};
}

// Events of `channel` in a log being written (0 while it cannot be read).
size_t eventsSoFar(const std::string& log, const std::string& channel) {
  size_t n = 0;
  try {
    EventLogReader reader(log);
    reader.setResync(true);
    LogEvent e;
    while (reader.next(&e)) n += e.channel == channel;
  } catch (const std::exception&) {
  }
  return n;
}

// Waits (up to 30 s) until the recording holds `n` messages of `channel`: the good stream flows,
// so that a message stamped a day ahead meets a stream it is off, not the first of one.
void awaitStream(const std::string& log, const std::string& channel, size_t n) {
  for (int i = 0; i < 300 && eventsSoFar(log, channel) < n; ++i) sleepS(0.1);
  ASSERT_GE(eventsSoFar(log, channel), n) << channel << " never flowed into " << log;
}

// The process's counter, in the last status it published (recorded in `log`).
int64_t statusCounter(const std::string& log, const std::string& status, const std::string& name) {
  const LastStatus s = lastStatus(log, status);
  EXPECT_TRUE(s.found) << status << " in " << log;
  return s.counter(name);
}

// The datagram attacks are counted in every node's status.
void expectDatagramRefusalsCounted(const std::string& log, const std::string& status) {
  EXPECT_GE(statusCounter(log, status, "net_refused_fragment_out_of_range"), 1) << status;
  EXPECT_GE(statusCounter(log, status, "net_refused_channel_unterminated"), 1) << status;
  EXPECT_GE(statusCounter(log, status, "net_refused"), 100) << status;
}

class HostileTest : public PrivateNetworkTest {
 protected:
  Launcher procs;

  std::string simLog(const fs::path& dir, const std::vector<std::string>& args) {
    const std::string log = (dir / "sim.lcmlog").string();
    std::vector<std::string> all = {"sim"};
    all.insert(all.end(), args.begin(), args.end());
    all.insert(all.end(), {"--out", log});
    EXPECT_EQ(sweepmap(all, dir / "sim.txt"), 0) << readFile(dir / "sim.txt");
    return log;
  }
  // `sweepmap record` of every channel on `url` (whose port is `port`), subscribed.
  pid_t startRecorder(const fs::path& dir, const std::string& url = kUrl,
                      const std::string& name = "recorder", uint16_t port = kPort) {
    return procs.startSubscriber(name,
                                 {binPath("sweepmap"), "record", "--preset", "all", "--out",
                                  (dir / name).string(), "--lcm-url", url},
                                 port);
  }
  // `sweepmap status --once --json` listening while the attacks are sent.
  pid_t startStatus() {
    return procs.startSubscriber("status",
                                 {binPath("sweepmap"), "status", "--once", "--json", "--window",
                                  "3", "--stale-s", "30", "--lcm-url", kUrl},
                                 kPort);
  }
};

// Rig A: the assembler, the mapper, the recorder and `sweepmap status` take every attack while a
// simulated run is played; the clouds and the map are those of the replay of that run.
TEST_F(HostileTest, RigAProcessesTakeEveryAttackAndTheRunStillEqualsReplay) {
  const auto dir = scratchDir("hostile_rig_a");
  procs.setDir(dir);
  const std::string sim_log = simLog(
      dir, {"--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "2", "--seed", "8"});
  const ProcessCommand proc{{"--rig", kRig, "--set", "motor.mode=1", "--lcm-url", kUrl}};
  const pid_t recorder = startRecorder(dir);
  const pid_t assembler = procs.startSubscriber("assembler", proc("assembler"), kPort);
  const pid_t mapper = procs.startSubscriber(
      "mapper", proc("mapper", {"--save", (dir / "live_map.bt").string()}), kPort);
  std::ofstream(dir / "notes.txt") << "not the mapper's\n";
  const pid_t status = startStatus();
  const std::vector<std::string> subscribed = {"LIDAR_SCAN",   "SCAN_WINDOW", "SWEEP_CLOUD",
                                               "SWEEP_STATUS", "MAP_SAVE",    "STATUS_ASSEMBLER"};
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(crashDatagrams(subscribed, 2000)));
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(hostileMessages()));
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(hostileSaves()));
  EXPECT_EQ(procs.wait(status, 20.0), 0) << procs.said(status);
  for (pid_t p : {recorder, assembler, mapper}) ASSERT_TRUE(procs.running(p)) << procs.said(p);

  const pid_t player = procs.start("logplayer", playerCommand(kUrl, sim_log));
  const std::string rec = (dir / "recorder" / "run").string();
  ASSERT_NO_FATAL_FAILURE(awaitStream(rec, channels::kLidarScan, 10));
  ASSERT_NO_FATAL_FAILURE(sendDatagrams({dayAhead(sim_log, channels::kLidarScan)}));
  ASSERT_EQ(procs.wait(player, 120.0), 0) << procs.said(player);
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(crashDatagrams(subscribed, 200)));  // and after
  procs.stopInOrder({{assembler, 10.0}, {mapper, 60.0}, {recorder, 10.0}}, 0.8);

  ASSERT_EQ(replayInto(dir / "offline", sim_log, {"--rig", kRig, "--set", "motor.mode=1"}), 0)
      << readFile(dir / "replay.txt");
  const Chunks live = chunksOf(rec);
  ASSERT_FALSE(live.empty()) << procs.said(recorder);
  EXPECT_TRUE(sameChunks(live, chunksOf((dir / "offline" / "derived.lcmlog").string())));
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", dir / "offline" / "map.bt"));
  // The recorder kept every raw message the player sent, byte for byte.
  EXPECT_TRUE(sameMessages(rec, sim_log, "SCAN_WINDOW", 1));
  // Every refusal is counted where a person looks: the processes' status.
  for (const char* s : {"STATUS_ASSEMBLER", "STATUS_MAPPER"}) expectDatagramRefusalsCounted(rec, s);
  EXPECT_EQ(statusCounter(rec, "STATUS_ASSEMBLER", "stamp_refused_LIDAR_SCAN"), 1);
  EXPECT_GE(statusCounter(rec, "STATUS_MAPPER", "invalid_MAP_SAVE"), 1);
  EXPECT_GE(statusCounter(rec, "STATUS_MAPPER", "invalid_SWEEP_STATUS"), 1);
  // 38 requests: the 8 bad names and all but one of the 30 sent within a second are refused.
  EXPECT_GE(statusCounter(rec, "STATUS_MAPPER", "refused_saves"), 37);
  EXPECT_EQ(readFile(dir / "notes.txt"), "not the mapper's\n");
  for (const char* bad : {"-rf", "notes.txt.bt", "evil\nname.bt"})
    EXPECT_FALSE(fs::exists(dir / bad));
  EXPECT_FALSE(fs::exists(dir.parent_path() / "escape.bt"));
  EXPECT_NE(procs.said(recorder).find("datagrams refused"), std::string::npos);
  // `sweepmap status` printed its snapshot, the hostile status messages counted, not shown.
  const nlohmann::json snapshot = nlohmann::json::parse(procs.said(status), nullptr, false);
  ASSERT_FALSE(snapshot.is_discarded()) << procs.said(status);
  EXPECT_GE(snapshot["malformed"].get<int64_t>(), 4) << procs.said(status);
  EXPECT_GE(snapshot["datagrams_refused"].get<int64_t>(), 100) << procs.said(status);
  EXPECT_TRUE(snapshot["processes"].contains("assembler")) << procs.said(status);
  EXPECT_FALSE(snapshot["processes"].contains("intruder")) << procs.said(status);
}

// Poses of ODOMETRY_POSE in a log.
std::vector<pose2d_t> posesOf(const std::string& log) {
  std::vector<pose2d_t> poses;
  EventLogReader reader(log);
  LogEvent e;
  while (reader.next(&e)) {
    pose2d_t p{};
    if (e.channel == channels::kOdometryPose && p.decode(e.data.data(), 0, e.data.size()) > 0) {
      poses.push_back(p);
    }
  }
  return poses;
}

// Rig B: the odometry (its EKF), the world assembler and the mapper take the attacks and an IMU,
// a WHEEL_TICKS and a LIDAR_SCAN message stamped a day ahead while a simulated drive is played.
// The clouds, the wheel odometry and the map equal the replay's; the EKF's poses too, but for
// `trusted`, false for the 2 s after the refused input (odometry.refused_input_window_s).
TEST_F(HostileTest, RigBOdometryAndAssemblerTakeEveryAttackAndTheDriveStillEqualsReplay) {
  const auto dir = scratchDir("hostile_rig_b");
  procs.setDir(dir);
  const std::string rig_b = sourcePath("config/rig_b.yaml");
  const std::string sim_log =
      simLog(dir, {"--rig", rig_b, "--scene", sourcePath("config/scene_lab.yaml"), "--set",
                   "sim.duration_s=6", "--seed", "5"});
  const ProcessCommand proc{{"--rig", rig_b, "--lcm-url", kUrl}};
  const pid_t recorder = startRecorder(dir);
  const pid_t odometry = procs.startSubscriber("odometry", proc("odometry", {"--from-lcm"}), kPort);
  const pid_t assembler = procs.startSubscriber("assembler", proc("assembler"), kPort);
  const pid_t mapper = procs.startSubscriber(
      "mapper", proc("mapper", {"--save", (dir / "live_map.bt").string()}), kPort);
  const std::vector<std::string> subscribed = {"IMU",           "WHEEL_TICKS", "LIDAR_SCAN",
                                               "ODOMETRY_POSE", "SWEEP_CLOUD", "MAP_SAVE"};
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(crashDatagrams(subscribed, 400)));
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(hostileMessages()));
  const pid_t player = procs.start("logplayer", playerCommand(kUrl, sim_log));
  const std::string rec = (dir / "recorder" / "run").string();
  ASSERT_NO_FATAL_FAILURE(awaitStream(rec, channels::kWheelTicks, 20));
  ASSERT_NO_FATAL_FAILURE(
      sendDatagrams({dayAhead(sim_log, channels::kImu), dayAhead(sim_log, channels::kWheelTicks),
                     dayAhead(sim_log, channels::kLidarScan)}));
  ASSERT_EQ(procs.wait(player, 120.0), 0) << procs.said(player);
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(crashDatagrams(subscribed, 100)));
  procs.stopInOrder({{odometry, 10.0}, {assembler, 10.0}, {mapper, 60.0}, {recorder, 10.0}}, 0.8);

  const auto offline = dir / "offline";
  ASSERT_EQ(replayInto(offline, sim_log, {"--rig", rig_b}), 0) << readFile(dir / "replay.txt");
  const std::string derived = (offline / "derived.lcmlog").string();
  for (const char* channel : {channels::kWheelOdometry, channels::kSweepCloud}) {
    EXPECT_TRUE(sameMessages(rec, derived, channel, 10)) << channel;
  }
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", offline / "map.bt"));
  const std::vector<pose2d_t> live = posesOf(rec), replayed = posesOf(derived);
  ASSERT_EQ(live.size(), replayed.size());
  size_t untrusted = 0;
  for (size_t i = 0; i < live.size(); ++i) {
    EXPECT_EQ(live[i].utime, replayed[i].utime) << i;
    EXPECT_EQ(live[i].x_m, replayed[i].x_m) << i;
    EXPECT_EQ(live[i].y_m, replayed[i].y_m) << i;
    EXPECT_EQ(live[i].theta_rad, replayed[i].theta_rad) << i;
    EXPECT_TRUE(replayed[i].trusted || !live[i].trusted) << i;
    untrusted += replayed[i].trusted && !live[i].trusted;
  }
  EXPECT_GT(untrusted, 10u);  // the refused input made the EKF say so
  for (const char* s : {"STATUS_ODOMETRY", "STATUS_WORLD_ASSEMBLER", "STATUS_MAPPER"}) {
    expectDatagramRefusalsCounted(rec, s);
  }
  EXPECT_EQ(statusCounter(rec, "STATUS_ODOMETRY", "stamp_refused_IMU"), 1);
  EXPECT_EQ(statusCounter(rec, "STATUS_ODOMETRY", "stamp_refused_WHEEL_TICKS"), 1);
  EXPECT_EQ(statusCounter(rec, "STATUS_ODOMETRY", "refused_input"), 2);
  EXPECT_EQ(statusCounter(rec, "STATUS_WORLD_ASSEMBLER", "stamp_refused_LIDAR_SCAN"), 1);
  EXPECT_GE(statusCounter(rec, "STATUS_MAPPER", "invalid_MAP_SAVE"), 1);
  // The drive went on: after the window the odometry said OK again.
  EXPECT_EQ(lastStatus(rec, "STATUS_ODOMETRY").message.health, +process_status_t::OK)
      << lastStatus(rec, "STATUS_ODOMETRY").message.detail;
}

// Rig C: the profile assembler and the mapper take the attacks and a PROFILE stamped a day ahead
// while a simulated test piece is played; the profiler (the device process) takes the datagram
// attacks on a port of its own while it scans, and finishes its sweep.
TEST_F(HostileTest, RigCProcessesTakeEveryAttackAndTheScanStillEqualsReplay) {
  const auto dir = scratchDir("hostile_rig_c");
  procs.setDir(dir);
  const std::string sim_log =
      simLog(dir, {"--rig", "rig_c", "--scene", "test_piece", "--seed", "6"});
  const ProcessCommand proc{{"--rig", "rig_c", "--lcm-url", kUrl}};
  const std::string profiler_url = "udpm://239.255.76.67:7668?ttl=0";
  const pid_t recorder = startRecorder(dir);
  const pid_t profiler_recorder = startRecorder(dir, profiler_url, "profiler_recorder", 7668);
  const pid_t assembler = procs.startSubscriber("assembler", proc("assembler"), kPort);
  const pid_t mapper = procs.startSubscriber(
      "mapper", proc("mapper", {"--save", (dir / "live_map.bt").string()}), kPort);
  const pid_t profiler =
      procs.startSubscriber("profiler",
                            {binPath("sweepmap-profiler"), "--rig", "rig_c", "--sim", "--sweeps",
                             "1", "--lcm-url", profiler_url},
                            7668);
  const std::vector<std::string> subscribed = {"PROFILE", "SWEEP_CLOUD", "MAP_SAVE",
                                               "STATUS_PROFILER"};
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(crashDatagrams(subscribed, 400)));
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(crashDatagrams(subscribed, 400), 7668));
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(hostileMessages()));
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(hostileSaves()));
  const pid_t player = procs.start("logplayer", playerCommand(kUrl, sim_log));
  const std::string rec = (dir / "recorder" / "run").string();
  ASSERT_NO_FATAL_FAILURE(awaitStream(rec, channels::kProfile, 20));
  ASSERT_NO_FATAL_FAILURE(sendDatagrams({dayAhead(sim_log, channels::kProfile)}));
  ASSERT_EQ(procs.wait(player, 120.0), 0) << procs.said(player);
  EXPECT_EQ(procs.wait(profiler, 60.0), 0) << procs.said(profiler);
  procs.stopInOrder(
      {{assembler, 10.0}, {mapper, 60.0}, {recorder, 10.0}, {profiler_recorder, 10.0}}, 0.8);

  const auto offline = dir / "offline";
  ASSERT_EQ(replayInto(offline, sim_log, {"--rig", "rig_c"}), 0) << readFile(dir / "replay.txt");
  EXPECT_TRUE(sameMessages(rec, (offline / "derived.lcmlog").string(), channels::kSweepCloud, 100));
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", offline / "map.bt"));
  for (const char* s : {"STATUS_PROFILE_ASSEMBLER", "STATUS_MAPPER"}) {
    expectDatagramRefusalsCounted(rec, s);
  }
  expectDatagramRefusalsCounted((dir / "profiler_recorder" / "run").string(), "STATUS_PROFILER");
  EXPECT_EQ(statusCounter(rec, "STATUS_PROFILE_ASSEMBLER", "stamp_refused_PROFILE"), 1);
  EXPECT_GE(statusCounter(rec, "STATUS_MAPPER", "refused_saves"), 37);
}

// With a shared key on every process, a forger on the LAN who replays the sensors' messages
// unsigned (or signs them with another key) reaches no node: the live clouds and map are those
// of the replay of the signed run's recording, and the forgeries are counted. The lidar and the
// motor (simulated devices) take the crash datagrams meanwhile.
TEST_F(HostileTest, WithAKeyForgedMessagesReachNoNode) {
  const auto dir = scratchDir("hostile_key");
  procs.setDir(dir);
  const std::string key = (dir / "lcm.key").string();
  std::ofstream(key) << std::string(64, 'a') << "\n";
  ASSERT_EQ(::chmod(key.c_str(), 0400), 0);
  const ProcessCommand proc{
      {"--rig", kRig, "--set", "motor.mode=1", "--lcm-url", kUrl, "--key-file", key}};
  // Each process is waited for until it listens, one at a time, so that the crash datagrams
  // below reach every one of them however loaded the machine is.
  const pid_t recorder =
      procs.startSubscriber("recorder",
                            {binPath("sweepmap"), "record", "--preset", "all", "--out",
                             (dir / "rec").string(), "--lcm-url", kUrl, "--key-file", key},
                            kPort);
  const pid_t assembler = procs.startSubscriber("assembler", proc("assembler"), kPort);
  const pid_t lidar = procs.startSubscriber(
      "lidar", proc("lidar", {"--sim", "--scene", kScene, "--seed", "3"}), kPort);
  sleepS(0.7);
  // The forger: another run's raw messages, unsigned, played during the signed run.
  const std::string forged = (dir / "forged.lcmlog").string();
  ASSERT_EQ(sweepmap({"sim", "--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "1",
                      "--seed", "99", "--out", forged}),
            0);
  const pid_t forger = procs.start("forger", playerCommand(kUrl, forged));
  const pid_t motor = procs.startSubscriber(
      "motor", proc("motor", {"--sim", "--sweeps", "2", "--seed", "3"}), kPort);
  // `sweepmap status` with the key reads the signed statuses.
  const pid_t status =
      procs.start("status", {binPath("sweepmap"), "status", "--once", "--json", "--window", "2.5",
                             "--lcm-url", kUrl, "--key-file", key});
  // The drivers' processes (lidar, motor) take the crash datagrams too, while they run.
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(
      crashDatagrams({"TRUTH_SHAFT", "LIDAR_SCAN", "MOTOR_STATE", "SCAN_WINDOW"}, 400)));
  EXPECT_EQ(procs.wait(status, 20.0), 0) << procs.said(status);
  const nlohmann::json snapshot = nlohmann::json::parse(procs.said(status), nullptr, false);
  ASSERT_FALSE(snapshot.is_discarded()) << procs.said(status);
  for (const char* p : {"assembler", "lidar", "motor"}) {
    EXPECT_TRUE(snapshot["processes"].contains(p)) << p << ": " << procs.said(status);
  }
  EXPECT_EQ(snapshot["malformed"].get<int64_t>(), 0) << procs.said(status);
  ASSERT_EQ(procs.wait(motor, 90.0), 0) << procs.said(motor);
  EXPECT_EQ(procs.wait(forger, 60.0), 0) << procs.said(forger);
  procs.stopInOrder({{lidar, 5.0}, {assembler, 10.0}, {recorder, 10.0}}, 0.8);

  const std::string rec = (dir / "rec" / "run").string();
  const Chunks live = chunksOf(rec);
  ASSERT_FALSE(live.empty()) << procs.said(assembler);
  ASSERT_EQ(replayInto(dir / "offline", rec, {"--rig", kRig, "--set", "motor.mode=1"}), 0)
      << readFile(dir / "replay.txt");
  EXPECT_TRUE(sameChunks(live, chunksOf((dir / "offline" / "derived.lcmlog").string())));
  const LastStatus s = lastStatus(rec, "STATUS_ASSEMBLER");
  ASSERT_TRUE(s.found);
  EXPECT_GT(s.counter("net_not_signed"), 100);
  int sweeps = 0;
  for (const auto& [k, bytes] : live) sweeps += k.second == 0;
  EXPECT_EQ(sweeps, 2);  // the forged sweep made none
  for (const char* status : {"STATUS_LIDAR", "STATUS_MOTOR", "STATUS_ASSEMBLER"}) {
    expectDatagramRefusalsCounted(rec, status);
  }
}

// The command line of a generated unit's ExecStart (our paths have no spaces to quote).
std::vector<std::string> execStart(const fs::path& unit) {
  std::istringstream text(readFile(unit));
  std::string line;
  while (std::getline(text, line)) {
    if (line.rfind("ExecStart=", 0) != 0) continue;
    std::istringstream words(line.substr(10));
    std::vector<std::string> argv;
    for (std::string w; words >> w;) argv.push_back(w);
    return argv;
  }
  ADD_FAILURE() << "no ExecStart in " << unit;
  return {};
}

// The units `sweepmap systemd` writes are secure by default: run as systemd would, a process
// refuses a key file its group or others may read (exit 2, naming the file), and with the key
// made private it hears only the deployment's hosts: this host (127.0.0.1) is not one of them,
// so everything it hears is dropped and counted.
TEST_F(HostileTest, GeneratedUnitsRefuseAReadableKeyAndHearOnlyTheHosts) {
  const auto dir = scratchDir("hostile_units");
  procs.setDir(dir);
  const std::string key = (dir / "lcm.key").string();
  std::ofstream(key) << std::string(64, 'b') << "\n";
  ASSERT_EQ(::chmod(key.c_str(), 0644), 0);
  std::ofstream(dir / "deploy.yaml")
      << "lcm_url: " << kUrl << "\nkey_file: " << key
      << "\nrestart: {delay_s: 0.5, max_delay_s: 10, stable_s: 60, watchdog_s: 5, "
         "stop_timeout_s: 30}\nhosts:\n  robot:\n    address: 10.77.0.9\n    processes:\n"
         "      - {name: assembler, command: sweepmap-assembler, args: [--rig, "
      << kRig << "]}\n";
  ASSERT_EQ(sweepmap({"systemd", (dir / "deploy.yaml").string(), "--host", "robot", "--out",
                      (dir / "units").string(), "--bin-dir",
                      fs::path(binPath("sweepmap")).parent_path().string()},
                     dir / "systemd.txt"),
            0)
      << readFile(dir / "systemd.txt");
  const std::vector<std::string> argv = execStart(dir / "units" / "sweepmap-assembler.service");
  const pid_t refused = procs.start("refused", argv);
  EXPECT_EQ(procs.wait(refused, 10.0), 2);
  EXPECT_NE(procs.said(refused).find(key + ": may be read or written by others"), std::string::npos)
      << procs.said(refused);

  ASSERT_EQ(::chmod(key.c_str(), 0400), 0);
  const std::string sim_log = simLog(
      dir, {"--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "1", "--seed", "8"});
  const pid_t recorder =
      procs.startSubscriber("recorder",
                            {binPath("sweepmap"), "record", "--preset", "all", "--out",
                             (dir / "rec").string(), "--lcm-url", kUrl, "--key-file", key},
                            kPort);
  const pid_t assembler = procs.startSubscriber("assembler", argv, kPort);
  ASSERT_EQ(procs.play(kUrl, sim_log, 60.0), 0) << procs.said("logplayer");
  sleepS(1.2);  // a status at 1 Hz after the last message
  procs.stopInOrder({{assembler, 10.0}, {recorder, 10.0}}, 0.3);
  const std::string rec = (dir / "rec" / "run").string();
  EXPECT_GT(statusCounter(rec, "STATUS_ASSEMBLER", "net_not_allowed"), 100);
  EXPECT_EQ(statusCounter(rec, "STATUS_ASSEMBLER", "messages_in"), 0);
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
