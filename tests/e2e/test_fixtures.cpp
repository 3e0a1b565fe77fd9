// The e2e fixtures themselves: the live-against-replay comparisons fail on what they are there
// to catch, the launcher stops processes in the order given and keeps what each said, and the
// private network is not the machine's.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "core/event_log.hpp"
#include "tests/e2e/fixtures.hpp"

namespace sweepmap {
namespace test {
namespace {

void writeLog(const fs::path& path, const std::vector<std::vector<uint8_t>>& messages) {
  EventLogWriter w(path.string());
  int64_t utime = 1000;
  for (const auto& m : messages) w.write(utime++, "SWEEP_CLOUD", m);
}

TEST(LiveAgainstReplay, SameMessagesCatchesADifferentByteAMissingMessageAndAnEmptyRun) {
  const fs::path dir = scratchDir("fixtures_messages");
  const auto log = [&](const std::string& name, const std::vector<std::vector<uint8_t>>& m) {
    writeLog(dir / name, m);
    return (dir / name).string();
  };
  const std::string a = log("a", {{1, 2}, {3}});
  EXPECT_TRUE(sameMessages(a, log("same", {{1, 2}, {3}}), "SWEEP_CLOUD"));
  const auto differ = sameMessages(a, log("differ", {{1, 2}, {4}}), "SWEEP_CLOUD");
  EXPECT_FALSE(differ);
  EXPECT_NE(std::string(differ.message()).find("1 of 2 messages differ"), std::string::npos);
  EXPECT_FALSE(sameMessages(a, log("short", {{1, 2}}), "SWEEP_CLOUD"));
  EXPECT_FALSE(sameMessages(a, log("reordered", {{3}, {1, 2}}), "SWEEP_CLOUD"));
  EXPECT_FALSE(sameMessages(log("empty1", {}), log("empty2", {}), "SWEEP_CLOUD"));
  EXPECT_FALSE(sameMessages(a, a, "SWEEP_CLOUD", 2)) << "more than 2 asked, 2 there";
}

TEST(LiveAgainstReplay, SameChunksCatchesAMissingAndADifferentChunk) {
  const Chunks live = {{{0, 0}, {1}}, {{0, 1}, {2}}};
  EXPECT_TRUE(sameChunks(live, live));
  EXPECT_FALSE(sameChunks(live, {{{0, 0}, {1}}}));
  EXPECT_FALSE(sameChunks(live, {{{0, 0}, {1}}, {{1, 1}, {2}}}));
  const auto differ = sameChunks(live, {{{0, 0}, {1}}, {{0, 1}, {9}}});
  EXPECT_FALSE(differ);
  EXPECT_NE(std::string(differ.message()).find("sweep 0 chunk 1 differs"), std::string::npos);
}

TEST(LiveAgainstReplay, SameBytesNeedsBothFilesAndTheSameBytes) {
  const fs::path dir = scratchDir("fixtures_bytes");
  std::ofstream(dir / "a") << "map";
  std::ofstream(dir / "b") << "map";
  std::ofstream(dir / "c") << "mop";
  EXPECT_TRUE(sameBytes(dir / "a", dir / "b"));
  EXPECT_FALSE(sameBytes(dir / "a", dir / "c"));
  EXPECT_FALSE(sameBytes(dir / "a", dir / "none"));
  EXPECT_FALSE(sameBytes(dir / "none", dir / "none2")) << "two missing maps are not equal";
}

// A shell that says it is ready once it has its SIGINT handler: on SIGINT it appends its name
// to `order` and exits with `status`.
pid_t startStoppable(Launcher& procs, const std::string& name, const fs::path& order,
                     int status = 0) {
  const std::string script = "trap 'echo " + name + " >> " + order.string() + "; exit " +
                             std::to_string(status) + "' INT; echo ready " + name +
                             "; while :; do sleep 0.02; done";
  const pid_t pid = procs.start(name, {"sh", "-c", script});
  while (procs.said(name).empty() && procs.running(pid)) sleepS(0.01);
  return pid;
}

TEST(Launcher, StopsInTheOrderGivenAndKeepsWhatEachSaid) {
  const fs::path dir = scratchDir("fixtures_launcher");
  Launcher procs;
  procs.setDir(dir);
  const fs::path order = dir / "order.txt";
  const pid_t logger = startStoppable(procs, "logger", order);
  const pid_t mapper = startStoppable(procs, "mapper", order);
  const pid_t lidar = startStoppable(procs, "lidar", order);
  procs.stopInOrder({{lidar, 5.0}, {mapper, 5.0}, {logger, 5.0}});
  EXPECT_EQ(readFile(order), "lidar\nmapper\nlogger\n");
  EXPECT_EQ(procs.said(mapper), "ready mapper\n");
  EXPECT_EQ(readFile(dir / "lidar.txt"), "ready lidar\n");
  EXPECT_FALSE(procs.running(logger));
}

TEST(Launcher, StopInOrderExpectsEachExitStatus) {
  const fs::path dir = scratchDir("fixtures_launcher_status");
  Launcher procs;
  procs.setDir(dir);
  const pid_t failing = startStoppable(procs, "failing", dir / "order.txt", 3);
  EXPECT_NONFATAL_FAILURE(procs.stopInOrder({{failing, 5.0}}), "failing (exit status 3) said:");
  const pid_t any = startStoppable(procs, "any", dir / "order.txt", 3);
  procs.stopInOrder({{any, 5.0, std::nullopt}});  // no expectation: no failure
  EXPECT_EQ(procs.stop(any, 1.0), 3);
}

class PrivateNetwork : public PrivateNetworkTest {};

// The test process is in a network namespace of its own (not its parent's), multicast routed
// to its `lo`.
TEST_F(PrivateNetwork, IsNotTheMachinesAndRoutesMulticastToLo) {
  const auto ns = [](const std::string& pid) {
    return fs::read_symlink("/proc/" + pid + "/ns/net").string();
  };
  EXPECT_NE(ns("self"), ns(std::to_string(::getppid())));  // ctest's, the machine's
  const fs::path dir = scratchDir("fixtures_network");
  Launcher procs;
  procs.setDir(dir);
  ASSERT_EQ(procs.wait(procs.start("route", {"ip", "route", "show", "224.0.0.0/4"}), 10.0), 0);
  EXPECT_NE(procs.said("route").find("dev lo"), std::string::npos) << procs.said("route");
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
