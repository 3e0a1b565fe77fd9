// The fixtures of the live end-to-end tests: a private network namespace for a test suite,
// the processes of a run (started with their output kept, stopped upstream first with a
// timeout each) and the comparison of what the live processes gave with what `sweepmap
// replay` gives from the same input (byte equality of messages, clouds and maps).
#pragma once

#include <gtest/gtest.h>
#include <sys/types.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sweepmap/process_status_t.hpp"
#include "tests/e2e/test_support.hpp"
#include "tools/ops/netns.hpp"
#include "tools/ops/process_group.hpp"

namespace sweepmap {
namespace test {

// The UDP port of kDefaultLcmUrl (processes/channels.hpp).
constexpr uint16_t kDefaultLcmPort = 7667;

// Waits `s` seconds: for the last messages to arrive (Launcher::startSubscriber waits for a
// subscriber to be ready).
void sleepS(double s);

// ---- Network namespaces ------------------------------------------------------------------

// A test suite whose process runs in a private network namespace (tools/ops/netns: unshare
// --net, `lo` up, 224.0.0.0/4 routed to it), entered once per test process, so LCM multicast
// never leaves it. Every test skips, saying why, where namespaces are unavailable.
class PrivateNetworkTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite();
  void SetUp() override;
};

// Mounts a tmpfs of `size` ("4m") on `dir` in a private mount namespace of this process (no
// other process sees it; it goes with the process). False with the reason where that is not
// possible.
bool mountPrivateTmpfs(const fs::path& dir, const std::string& size, std::string* why);

// ---- Processes ---------------------------------------------------------------------------

// Command lines of sweepmap-NAME processes that share options (the rig, its --set, the LCM
// URL): build/bin/sweepmap-NAME, the process's own arguments, then the shared ones.
class ProcessCommand {
 public:
  explicit ProcessCommand(std::vector<std::string> shared) : shared_(std::move(shared)) {}
  std::vector<std::string> operator()(const std::string& name,
                                      std::vector<std::string> args = {}) const;

 private:
  std::vector<std::string> shared_;
};

// lcm-logger writing `file` (overwriting it), all channels or those matching `channels`.
std::vector<std::string> loggerCommand(const std::string& url, const std::string& file,
                                       const std::string& channels = "");

// lcm-logplayer of `log`, `options` before it ("--speed=10").
std::vector<std::string> playerCommand(const std::string& url, const std::string& log,
                                       const std::vector<std::string>& options = {});

// One process to stop, how long it may take, and the exit status it must give (none: any).
struct Stop {
  pid_t pid;
  double timeout_s;
  std::optional<int> status = 0;
};

// The processes of one test run. Each runs with its output (stdout and stderr) in
// DIR/NAME.txt, in this process's network namespace or in a given one; whatever still runs
// when the launcher goes is killed.
class Launcher {
 public:
  // Where the outputs go; set before the first start.
  void setDir(const fs::path& dir) { dir_ = dir; }
  pid_t start(const std::string& name, const std::vector<std::string>& argv,
              const NetworkNamespace* ns = nullptr);
  // start(), then waits until the process has bound a socket of its own on UDP `port` in its
  // network namespace (`ns`, or this process's) (an LCM subscriber is ready: what is sent next
  // reaches it). A test failure, naming the process and what it said, if none is bound within
  // timeout_s.
  pid_t startSubscriber(const std::string& name, const std::vector<std::string>& argv,
                        uint16_t port, double timeout_s = 30.0,
                        const NetworkNamespace* ns = nullptr);
  // What the process said so far (by its pid or its name).
  std::string said(pid_t pid) const { return said(group_.name(pid)); }
  std::string said(const std::string& name) const;
  // Its exit status, or -1 if it still runs after timeout_s.
  int wait(pid_t pid, double timeout_s) { return group_.wait(pid, timeout_s); }
  // SIGINT, then SIGKILL after timeout_s; the exit status (128 + signal if killed).
  int stop(pid_t pid, double timeout_s) { return group_.stop(pid, timeout_s); }
  bool running(pid_t pid) { return group_.running(pid); }
  // lcm-logplayer of `log` ("logplayer", `options` before the log) run to its end; its exit
  // status, -1 if it did not end within timeout_s.
  int play(const std::string& url, const std::string& log, double timeout_s,
           const std::vector<std::string>& options = {});
  // After drain_s (the last messages of a finished source reach everyone), stops `stops` in
  // the order given, upstream first, 0.3 s apart so each hands its last messages on before
  // the next one stops; expects each exit status, naming the process and what it said.
  void stopInOrder(const std::vector<Stop>& stops, double drain_s = 0.0);

 private:
  fs::path dir_;
  ProcessGroup group_;
};

// ---- Live against replay -----------------------------------------------------------------

// `sweepmap replay LOG ARGS --out OUT --no-plots`, its output in OUT/../replay.txt; the exit
// status.
int replayInto(const fs::path& out, const std::string& log, const std::vector<std::string>& args);

// The messages of `channel` in the two logs are the same bytes in the same order, and the
// offline log has more than `more_than` of them.
::testing::AssertionResult sameMessages(const std::string& live_log, const std::string& offline_log,
                                        const std::string& channel, size_t more_than = 0);

// SWEEP_CLOUD chunk payloads of a log by (sweep, chunk).
using Chunks = std::map<std::pair<int64_t, int>, std::vector<uint8_t>>;
Chunks chunksOf(const std::string& log);
// The same chunks on both sides (the same (sweep, chunk) keys), byte for byte.
::testing::AssertionResult sameChunks(const Chunks& live, const Chunks& offline);

// Two files hold the same bytes (a live mapper's map and the replay's); both must exist.
::testing::AssertionResult sameBytes(const fs::path& live, const fs::path& offline);

// The last message of a status channel (STATUS_<NAME>) in a log, with its counters by name;
// found is false when the log has none or the last does not decode.
struct LastStatus {
  bool found = false;
  process_status_t message;
  std::map<std::string, int64_t> counters;
  int64_t counter(const std::string& name, int64_t missing = 0) const;
};
LastStatus lastStatus(const std::string& log, const std::string& channel);

}  // namespace test
}  // namespace sweepmap
