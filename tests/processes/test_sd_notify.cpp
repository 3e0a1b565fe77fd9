// sd_notify without libsystemd: the datagrams reach a socket bound here (a path and the
// abstract namespace), the watchdog interval follows WATCHDOG_USEC/WATCHDOG_PID, and the live
// runner's worker loop says READY=1, WATCHDOG=1 and STOPPING=1 — and stops pinging while a
// node holds the worker.
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <vector>

#include "processes/live_runner.hpp"
#include "processes/sd_notify.hpp"

namespace sweepmap {
namespace {

using Clock = std::chrono::steady_clock;

// A datagram socket bound to `name` ('@' first: abstract), with NOTIFY_SOCKET pointing at it.
class NotifySocket {
 public:
  explicit NotifySocket(const std::string& name) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path, name.data(), name.size());
    const bool abstract = name[0] == '@';
    if (abstract)
      addr.sun_path[0] = '\0';
    else
      ::unlink(name.c_str());
    const auto len =
        static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + name.size() + (abstract ? 0 : 1));
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&addr), len), 0) << std::strerror(errno);
    ::setenv("NOTIFY_SOCKET", name.c_str(), 1);
  }
  ~NotifySocket() {
    ::close(fd_);
    ::unsetenv("NOTIFY_SOCKET");
    ::unsetenv("WATCHDOG_USEC");
    ::unsetenv("WATCHDOG_PID");
  }
  // The next datagram within timeout_ms, or "" if none.
  std::string receive(int timeout_ms = 2000) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) != 1) return "";
    char buffer[4096];
    const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
    return n > 0 ? std::string(buffer, static_cast<size_t>(n)) : "";
  }

 private:
  int fd_ = -1;
};

TEST(SdNotify, SendsToAnAbstractSocket) {
  NotifySocket s("@sweepmap-test-notify-" + std::to_string(::getpid()));
  EXPECT_TRUE(sdNotify("READY=1"));
  EXPECT_EQ(s.receive(), "READY=1");
}

TEST(SdNotify, SendsToASocketFile) {
  const std::string path = "/tmp/sweepmap-test-notify-" + std::to_string(::getpid());
  {
    NotifySocket s(path);
    EXPECT_TRUE(sdNotify("STATUS=working\nWATCHDOG=1"));
    EXPECT_EQ(s.receive(), "STATUS=working\nWATCHDOG=1");
  }
  ::unlink(path.c_str());
}

TEST(SdNotify, NothingWithoutASocket) {
  ::unsetenv("NOTIFY_SOCKET");
  EXPECT_FALSE(sdNotify("READY=1"));
  ::setenv("NOTIFY_SOCKET", "@sweepmap-test-nobody-listens", 1);
  EXPECT_FALSE(sdNotify("READY=1"));  // connection refused: no such socket
  ::unsetenv("NOTIFY_SOCKET");
}

TEST(SdNotify, WatchdogIntervalIsOnlyForTheNamedPid) {
  ::setenv("WATCHDOG_USEC", "4000000", 1);
  ::unsetenv("WATCHDOG_PID");
  EXPECT_EQ(sdWatchdogUsec(), 4000000);
  ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
  EXPECT_EQ(sdWatchdogUsec(), 4000000);
  ::setenv("WATCHDOG_PID", std::to_string(::getpid() + 1).c_str(), 1);
  EXPECT_EQ(sdWatchdogUsec(), 0);  // meant for another process (our parent)
  ::unsetenv("WATCHDOG_PID");
  ::setenv("WATCHDOG_USEC", "soon", 1);
  EXPECT_EQ(sdWatchdogUsec(), 0);
  ::unsetenv("WATCHDOG_USEC");
  EXPECT_EQ(sdWatchdogUsec(), 0);
}

TEST(SdNotify, NotifierPingsAtHalfTheWatchdogInterval) {
  NotifySocket s("@sweepmap-test-notifier-" + std::to_string(::getpid()));
  ::setenv("WATCHDOG_USEC", "1000000", 1);
  SdNotifier n;
  EXPECT_EQ(n.pingInterval(), std::chrono::milliseconds(500));
  n.ready();
  EXPECT_EQ(s.receive(), "READY=1");
  const auto t0 = Clock::now();
  n.alive(t0 + std::chrono::milliseconds(499));  // too early
  n.alive(t0 + std::chrono::milliseconds(600));
  EXPECT_EQ(s.receive(), "WATCHDOG=1");
  n.alive(t0 + std::chrono::milliseconds(700));  // 100 ms after the last one
  n.stopping();
  EXPECT_EQ(s.receive(), "STOPPING=1");  // the 700 ms call sent nothing before it
}

// A node that holds the worker for `hang_ms` in one tick once asked to.
class HangingNode : public Node {
 public:
  HangingNode() : Node("hanging") {}
  std::vector<std::string> subscriptions() const override { return {}; }
  std::atomic<bool> hang{false};
  std::atomic<bool> hung{false};

 protected:
  void handle(const Message&, Outbox&) override {}
  void advance(int64_t, Outbox&) override {
    if (hang.exchange(false)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(600));
      hung = true;
    }
  }
};

TEST(SdNotify, LiveRunnerPingsFromItsWorkerLoopOnly) {
  NotifySocket s("@sweepmap-test-live-" + std::to_string(::getpid()));
  ::setenv("WATCHDOG_USEC", "40000", 1);  // a ping at least every 20 ms
  lcm::LCM lcm("memq://");
  HangingNode node;
  LiveOptions options("memq://");
  options.tick_period_ms = 5;
  const auto start = Clock::now();
  options.should_stop = [&] {
    if (Clock::now() - start > std::chrono::milliseconds(300) && !node.hung) node.hang = true;
    return node.hung && Clock::now() - start > std::chrono::milliseconds(1200);
  };
  std::vector<std::pair<Clock::time_point, std::string>> got;
  std::thread listener([&] {
    for (std::string m; !(m = s.receive(5000)).empty();) {
      got.emplace_back(Clock::now(), m);
      if (m == "STOPPING=1") break;
    }
  });
  EXPECT_EQ(runLive(lcm, {&node}, options), 0);
  listener.join();
  ASSERT_GE(got.size(), 3u);
  EXPECT_EQ(got.front().second, "READY=1");
  EXPECT_EQ(got.back().second, "STOPPING=1");
  int pings = 0;
  Clock::duration longest_gap{0};
  for (size_t i = 1; i + 1 < got.size(); ++i) {
    EXPECT_EQ(got[i].second, "WATCHDOG=1");
    ++pings;
    longest_gap = std::max(longest_gap, got[i].first - got[i - 1].first);
  }
  EXPECT_GE(pings, 5);
  // The node held the worker for 600 ms: no ping came meanwhile.
  EXPECT_GE(longest_gap, std::chrono::milliseconds(550));
}

// LiveOptions::healthy false (a device thread stuck): the worker withholds its pings.
TEST(SdNotify, AnUnhealthyProcessWithholdsItsPings) {
  NotifySocket s("@sweepmap-test-unhealthy-" + std::to_string(::getpid()));
  ::setenv("WATCHDOG_USEC", "20000", 1);
  lcm::LCM lcm("memq://");
  HangingNode node;
  LiveOptions options("memq://");
  options.tick_period_ms = 5;
  options.healthy = [] { return false; };
  const auto start = Clock::now();
  options.should_stop = [&] { return Clock::now() - start > std::chrono::milliseconds(300); };
  EXPECT_EQ(runLive(lcm, {&node}, options), 0);
  EXPECT_EQ(s.receive(), "READY=1");
  EXPECT_EQ(s.receive(), "STOPPING=1");  // and no WATCHDOG=1 between
}

}  // namespace
}  // namespace sweepmap
