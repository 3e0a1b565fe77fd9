// Hostile traffic on the robot's network (issue 21), in a private network namespace: the
// datagrams that crash every liblcm 1.3.1 receiver, and a flood of malformed ones, sent while
// the live processes and the recorder run. No process dies, every refusal is counted in the
// status, and the good traffic afterwards gives exactly what `sweepmap replay` gives. With a
// shared key, forged (unsigned) copies of the sensors' messages never reach a node.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <random>

#include "core/event_log.hpp"
#include "processes/channels.hpp"
#include "tests/e2e/fixtures.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");
const std::string kUrl = kDefaultLcmUrl;
constexpr uint16_t kPort = 7667;  // kDefaultLcmUrl's

using Bytes = std::vector<uint8_t>;

// Sends datagrams to LCM's group from a socket of their own, as another host on the LAN would.
void sendDatagrams(const std::vector<Bytes>& datagrams) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(kPort);
  inet_pton(AF_INET, "239.255.76.67", &to.sin_addr);
  for (size_t i = 0; i < datagrams.size(); ++i) {
    const Bytes& d = datagrams[i];
    ::sendto(fd, d.data(), d.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to);
    if (i % 100 == 99) sleepS(0.002);  // a flood, not a socket-buffer overflow test
  }
  ::close(fd);
}

void putU32(Bytes& b, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>(v >> s));
}

// Fragment 0 of an LC03 message on `channel` with offset 0xFFFFFFFF, 131 bytes: liblcm 1.3.1's
// 32-bit check wraps and its memcpy lands 4 GiB before the buffer.
Bytes offsetWrap(const std::string& channel) {
  Bytes b;
  putU32(b, 0x4c433033);
  putU32(b, 1);
  putU32(b, 100000);
  putU32(b, 0xFFFFFFFFu);
  b.insert(b.end(), {0, 0, 0, 2});
  b.insert(b.end(), channel.begin(), channel.end());
  b.push_back(0);
  b.resize(131, 0x41);
  return b;
}

// An LC02 whose channel has no NUL: liblcm reads past the datagram.
Bytes unterminated(const std::string& channel) {
  Bytes b;
  putU32(b, 0x4c433032);
  putU32(b, 2);
  b.insert(b.end(), channel.begin(), channel.end());
  return b;
}

// Every attack we know of on the channels the processes subscribe to, and random headers.
std::vector<Bytes> attack() {
  std::vector<Bytes> d;
  for (const char* channel : {"LIDAR_SCAN", "SCAN_WINDOW", "SWEEP_CLOUD", "MAP_SAVE"}) {
    d.push_back(offsetWrap(channel));
    d.push_back(unterminated(channel));
  }
  std::mt19937 rng(21);
  for (int i = 0; i < 2000; ++i) {
    Bytes b = i % 2 ? offsetWrap("LIDAR_SCAN") : unterminated("SWEEP_CLOUD");
    for (int e = 0; e < 3; ++e) b[rng() % std::min<size_t>(b.size(), 24)] = rng();
    d.push_back(std::move(b));
  }
  return d;
}

class HostileTest : public PrivateNetworkTest {
 protected:
  Launcher procs;

  std::string simLog(const fs::path& dir) {
    const std::string log = (dir / "sim.lcmlog").string();
    EXPECT_EQ(sweepmap({"sim", "--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "2",
                        "--seed", "8", "--out", log}),
              0);
    return log;
  }
};

TEST_F(HostileTest, CrashDatagramsStopNoProcessAndTheRunStillEqualsReplay) {
  const auto dir = scratchDir("hostile_crash");
  procs.setDir(dir);
  const std::string sim_log = simLog(dir);
  const ProcessCommand proc{{"--rig", kRig, "--set", "motor.mode=1", "--lcm-url", kUrl}};
  const pid_t recorder =
      procs.start("recorder", {binPath("sweepmap"), "record", "--preset", "all", "--out",
                               (dir / "rec").string(), "--lcm-url", kUrl});
  const pid_t assembler = procs.start("assembler", proc("assembler"));
  const pid_t mapper =
      procs.start("mapper", proc("mapper", {"--save", (dir / "live_map.bt").string()}));
  sleepS(0.7);
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(attack()));
  sleepS(0.5);
  for (pid_t p : {recorder, assembler, mapper}) ASSERT_TRUE(procs.running(p)) << procs.said(p);
  ASSERT_EQ(procs.play(kUrl, sim_log, 120.0), 0) << procs.said("logplayer");
  ASSERT_NO_FATAL_FAILURE(sendDatagrams(attack()));  // and again, after the good traffic
  procs.stopInOrder({{assembler, 10.0}, {mapper, 60.0}, {recorder, 10.0}}, 0.8);

  const std::string rec = (dir / "rec" / "run").string();
  ASSERT_EQ(replayInto(dir / "offline", sim_log, {"--rig", kRig, "--set", "motor.mode=1"}), 0)
      << readFile(dir / "replay.txt");
  const Chunks live = chunksOf(rec);
  ASSERT_FALSE(live.empty()) << procs.said(recorder);
  EXPECT_TRUE(sameChunks(live, chunksOf((dir / "offline" / "derived.lcmlog").string())));
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", dir / "offline" / "map.bt"));
  // The recorder kept every raw message the player sent, byte for byte.
  EXPECT_TRUE(sameMessages(rec, sim_log, "LIDAR_SCAN", 10));
  // Every refusal is counted where a person looks: the processes' status.
  for (const char* status : {"STATUS_ASSEMBLER", "STATUS_MAPPER"}) {
    const LastStatus s = lastStatus(rec, status);
    ASSERT_TRUE(s.found) << status;
    EXPECT_GE(s.counter("net_refused"), 1000) << status;
    EXPECT_GE(s.counter("net_refused_fragment_out_of_range"), 1) << status;
    EXPECT_GE(s.counter("net_refused_channel_unterminated"), 1) << status;
  }
  EXPECT_NE(procs.said(recorder).find("datagrams refused"), std::string::npos);
}

// With a shared key on every process, a forger on the LAN who replays the sensors' messages
// unsigned (or signs them with another key) reaches no node: the live clouds and map are those
// of the replay of the signed run's recording, and the forgeries are counted.
TEST_F(HostileTest, WithAKeyForgedMessagesReachNoNode) {
  const auto dir = scratchDir("hostile_key");
  procs.setDir(dir);
  const std::string key = (dir / "lcm.key").string();
  std::ofstream(key) << std::string(64, 'a') << "\n";
  ASSERT_EQ(::chmod(key.c_str(), 0600), 0);
  const ProcessCommand proc{
      {"--rig", kRig, "--set", "motor.mode=1", "--lcm-url", kUrl, "--key-file", key}};
  const pid_t recorder =
      procs.start("recorder", {binPath("sweepmap"), "record", "--preset", "all", "--out",
                               (dir / "rec").string(), "--lcm-url", kUrl, "--key-file", key});
  const pid_t assembler = procs.start("assembler", proc("assembler"));
  const pid_t lidar =
      procs.start("lidar", proc("lidar", {"--sim", "--scene", kScene, "--seed", "3"}));
  sleepS(0.7);
  // The forger: another run's raw messages, unsigned, played during the signed run.
  const std::string forged = (dir / "forged.lcmlog").string();
  ASSERT_EQ(sweepmap({"sim", "--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "1",
                      "--seed", "99", "--out", forged}),
            0);
  const pid_t forger = procs.start("forger", playerCommand(kUrl, forged));
  const pid_t motor =
      procs.start("motor", proc("motor", {"--sim", "--sweeps", "2", "--seed", "3"}));
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
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
