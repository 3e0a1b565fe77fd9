#include "tests/e2e/fixtures.hpp"

#include <sched.h>
#include <sys/mount.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "processes/channels.hpp"
#include "sweepmap/cloud_chunk_t.hpp"

namespace sweepmap {
namespace test {

void sleepS(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

// ---- Network namespaces ------------------------------------------------------------------

namespace {

struct PrivateNetwork {
  bool ok = false;
  std::string why;
};

// Entered by the first suite that asks; the later ones find the process in it.
const PrivateNetwork& privateNetwork() {
  static PrivateNetwork network;
  static std::once_flag once;
  std::call_once(once, [] { network.ok = enterPrivateNetwork(&network.why); });
  return network;
}

}  // namespace

void PrivateNetworkTest::SetUpTestSuite() { privateNetwork(); }

void PrivateNetworkTest::SetUp() {
  if (!privateNetwork().ok)
    GTEST_SKIP() << "no private network namespace: " << privateNetwork().why;
}

bool mountPrivateTmpfs(const fs::path& dir, const std::string& size, std::string* why) {
  const std::string options = "size=" + size;
  const char* step = nullptr;
  if (::unshare(CLONE_NEWNS) != 0) {
    step = "unshare(CLONE_NEWNS)";
  } else if (::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) {
    step = "making / private";
  } else if (::mount("tmpfs", dir.c_str(), "tmpfs", 0, options.c_str()) != 0) {
    step = "mounting the tmpfs";
  }
  if (step != nullptr) *why = std::string(step) + ": " + std::strerror(errno);
  return step == nullptr;
}

// ---- Processes ---------------------------------------------------------------------------

std::vector<std::string> ProcessCommand::operator()(const std::string& name,
                                                    std::vector<std::string> args) const {
  args.insert(args.begin(), binPath("sweepmap-" + name));
  args.insert(args.end(), shared_.begin(), shared_.end());
  return args;
}

namespace {

// The sockets bound to UDP `port` in the calling thread's network namespace
// (/proc/thread-self/net/udp: one line per socket, local address as hex "ADDR:PORT").
size_t udpSocketsOn(uint16_t port) {
  std::ifstream table("/proc/thread-self/net/udp");
  std::string line;
  std::getline(table, line);  // the header
  size_t n = 0;
  while (std::getline(table, line)) {
    std::istringstream fields(line);
    std::string slot, local;
    fields >> slot >> local;
    const size_t colon = local.find(':');
    if (colon != std::string::npos && std::stoul(local.substr(colon + 1), nullptr, 16) == port) ++n;
  }
  return n;
}

}  // namespace

pid_t Launcher::startSubscriber(const std::string& name, const std::vector<std::string>& argv,
                                uint16_t port, double timeout_s, const NetworkNamespace* ns) {
  const auto sockets = [&] {
    size_t n = 0;
    if (ns == nullptr) return udpSocketsOn(port);
    ns->run([&] { n = udpSocketsOn(port); });
    return n;
  };
  const size_t before = sockets();
  const pid_t pid = start(name, argv, ns);
  for (double t = 0; t < timeout_s && sockets() <= before && running(pid); t += 0.05) sleepS(0.05);
  EXPECT_GT(sockets(), before) << name << " bound no socket on UDP port " << port << " within "
                               << timeout_s << " s: " << said(pid);
  return pid;
}

std::vector<std::string> loggerCommand(const std::string& url, const std::string& file,
                                       const std::string& channels) {
  std::vector<std::string> argv = {"lcm-logger", "--lcm-url=" + url, "-f"};
  if (!channels.empty()) argv.insert(argv.end(), {"-c", channels});
  argv.push_back(file);
  return argv;
}

pid_t Launcher::start(const std::string& name, const std::vector<std::string>& argv,
                      const NetworkNamespace* ns) {
  const std::string output = (dir_ / (name + ".txt")).string();
  if (ns == nullptr) return group_.start(name, argv, output);
  pid_t pid = -1;
  ns->run([&] { pid = group_.start(name, argv, output); });
  return pid;
}

std::string Launcher::said(const std::string& name) const {
  return readFile(dir_ / (name + ".txt"));
}

std::vector<std::string> playerCommand(const std::string& url, const std::string& log,
                                       const std::vector<std::string>& options) {
  std::vector<std::string> argv = {"lcm-logplayer"};
  argv.insert(argv.end(), options.begin(), options.end());
  argv.insert(argv.end(), {"--lcm-url=" + url, log});
  return argv;
}

int Launcher::play(const std::string& url, const std::string& log, double timeout_s,
                   const std::vector<std::string>& options) {
  return wait(start("logplayer", playerCommand(url, log, options)), timeout_s);
}

void Launcher::stopInOrder(const std::vector<Stop>& stops, double drain_s) {
  sleepS(drain_s);
  for (size_t i = 0; i < stops.size(); ++i) {
    if (i > 0) sleepS(0.3);
    const Stop& s = stops[i];
    const int status = stop(s.pid, s.timeout_s);
    if (s.status) {
      EXPECT_EQ(status, *s.status)
          << group_.name(s.pid) << " (" << group_.describeExit(s.pid) << ") said:\n"
          << said(s.pid);
    }
  }
}

// ---- Live against replay -----------------------------------------------------------------

int replayInto(const fs::path& out, const std::string& log, const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"replay", log};
  argv.insert(argv.end(), args.begin(), args.end());
  argv.insert(argv.end(), {"--out", out.string(), "--no-plots"});
  return sweepmap(argv, out.parent_path() / "replay.txt");
}

::testing::AssertionResult sameMessages(const std::string& live_log, const std::string& offline_log,
                                        const std::string& channel, size_t more_than) {
  const auto live = readChannel(live_log, channel);
  const auto offline = readChannel(offline_log, channel);
  if (offline.size() <= more_than) {
    return ::testing::AssertionFailure() << channel << ": " << offline.size()
                                         << " messages offline, expected more than " << more_than;
  }
  if (live.size() != offline.size()) {
    return ::testing::AssertionFailure()
           << channel << ": " << live.size() << " messages live, " << offline.size() << " offline";
  }
  size_t differ = 0;
  for (size_t i = 0; i < live.size(); ++i) differ += live[i].data != offline[i].data;
  if (differ != 0) {
    return ::testing::AssertionFailure() << channel << ": " << differ << " of " << live.size()
                                         << " messages differ between live and offline";
  }
  return ::testing::AssertionSuccess() << channel << ": " << live.size() << " messages equal";
}

Chunks chunksOf(const std::string& log) {
  Chunks out;
  for (const auto& m : readChannel(log, channels::kSweepCloud)) {
    cloud_chunk_t c;
    EXPECT_TRUE(decodeMessage(m, &c)) << log;
    out[{c.sweep_id, c.chunk_index}] = m.data;
  }
  return out;
}

::testing::AssertionResult sameChunks(const Chunks& live, const Chunks& offline) {
  if (live.size() != offline.size()) {
    return ::testing::AssertionFailure()
           << live.size() << " chunks live, " << offline.size() << " offline";
  }
  for (const auto& [key, bytes] : live) {
    const auto other = offline.find(key);
    const std::string where =
        "sweep " + std::to_string(key.first) + " chunk " + std::to_string(key.second);
    if (other == offline.end()) return ::testing::AssertionFailure() << where << ": not offline";
    if (other->second != bytes) {
      return ::testing::AssertionFailure() << where << " differs between live and offline";
    }
  }
  return ::testing::AssertionSuccess() << live.size() << " chunks equal";
}

::testing::AssertionResult sameBytes(const fs::path& live, const fs::path& offline) {
  for (const fs::path& p : {live, offline}) {
    if (!fs::exists(p)) return ::testing::AssertionFailure() << p.string() << " does not exist";
  }
  const std::string a = readFile(live), b = readFile(offline);
  if (a != b) {
    return ::testing::AssertionFailure()
           << live.string() << " (" << a.size() << " bytes) differs from " << offline.string()
           << " (" << b.size() << " bytes)";
  }
  return ::testing::AssertionSuccess() << a.size() << " bytes equal";
}

int64_t LastStatus::counter(const std::string& name, int64_t missing) const {
  const auto it = counters.find(name);
  return it == counters.end() ? missing : it->second;
}

LastStatus lastStatus(const std::string& log, const std::string& channel) {
  LastStatus s;
  const auto messages = readChannel(log, channel);
  if (messages.empty() || !decodeMessage(messages.back(), &s.message)) return s;
  s.found = true;
  for (int i = 0; i < s.message.ncounters; ++i) {
    s.counters[s.message.counter_names[i]] = s.message.counter_values[i];
  }
  return s;
}

}  // namespace test
}  // namespace sweepmap
