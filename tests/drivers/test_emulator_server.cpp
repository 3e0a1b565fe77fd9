// The emulator's link (tools/emulate/emulator_server.hpp) on its own clock: what it says when
// it cannot keep real time, and what its pty lost.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>

#include "tools/emulate/emulator_server.hpp"

namespace sweepmap {
namespace {

// Streams a byte per millisecond of its clock, as a scanning lidar streams its samples: after a
// stall, all of that time's bytes at once.
class StreamingDevice : public EmulatedLidar {
 public:
  void receive(const uint8_t*, size_t, int64_t, std::string*) override {}
  void advance(int64_t now_us, std::string* out) override {
    if (last_us_ >= 0) out->append(size_t((now_us - last_us_) / 1000), '\x55');
    last_us_ = now_us;
  }
  void reset(int64_t) override {}

 private:
  int64_t last_us_ = -1;
};

// The pty link served for `duration_s` of a clock that moves `step_us` per reading and, at the
// `stall_at`-th reading, jumps by `stall_us` (the emulator not scheduled); what it printed.
std::string serveWithClock(int64_t step_us, int stall_at, int64_t stall_us, double duration_s) {
  int64_t now = 0;
  int readings = 0;
  const std::function<int64_t()> clock = [&] {
    now += ++readings == stall_at ? stall_us : step_us;
    return now;
  };
  ServerOptions options;
  options.pty = true;
  options.tick_us = 0;
  options.duration_s = duration_s;
  std::ostringstream info;
  std::atomic<bool> stop{false};
  serveEmulator([](int64_t) { return std::make_unique<StreamingDevice>(); }, options, LinkFaults{},
                clock, stop, info);
  return info.str();
}

// The bytes the pty had no room for, before a host opened it and after, from its report.
struct Unread {
  size_t total = 0, before = 0, after = 0;
};
Unread unreadOf(const std::string& said) {
  Unread u;
  const size_t at = said.find("emulator: the pty had no room for ");
  EXPECT_NE(at, std::string::npos) << said;
  if (at == std::string::npos) return u;
  EXPECT_EQ(std::sscanf(said.c_str() + at,
                        "emulator: the pty had no room for %zu of the bytes the device sent: %zu "
                        "before a host opened it (it started late, or never), %zu after",
                        &u.total, &u.before, &u.after),
            3)
      << said;
  return u;
}

TEST(EmulatorServer, SaysWhenItFellBehindRealTime) {
  // Nobody reads the pty. Its buffer holds the 3 s kept in real time (3 kB); the 100 s stall's
  // burst (100 kB) overflows it, and the report counts what was lost.
  const std::string said = serveWithClock(5000, 200, 100000000, 103.0);
  EXPECT_NE(said.find("emulator: serial device at "), std::string::npos) << said;
  // The stall and the clock's step after it: 100 s and a bit.
  EXPECT_NE(said.find("emulator: could not keep real time: stalled 1 time, for up to 100.0"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find(" of them lost (the link's buffer was full)"), std::string::npos) << said;
  EXPECT_EQ(said.find("stalled", said.find("stalled") + 1), std::string::npos) << said;  // once
}

// Nobody opens the pty: after a stall's burst fills it, the 39 s that follow lose most of their
// bytes, all of them before a host opened it (the burst's own are counted apart).
TEST(EmulatorServer, WithNoHostEveryLossIsBeforeAHostOpenedThePty) {
  const std::string said = serveWithClock(25000, 40, 100000000, 140.0);
  EXPECT_NE(said.find(" of them lost (the link's buffer was full)"), std::string::npos) << said;
  const Unread u = unreadOf(said);
  EXPECT_GT(u.before, 10000u) << said;
  EXPECT_EQ(u.after, 0u) << said;
}

TEST(EmulatorServer, KeepingRealTimeSaysNothingOfIt) {
  const std::string said = serveWithClock(5000, -1, 0, 3.0);
  EXPECT_EQ(said.find("real time"), std::string::npos) << said;
}

// A host that opens the pty 50 s in, reads what is queued once and never again: the bytes the
// pty had no room for before it opened it (a host that started late) and after (a host that
// did not read in time) are told apart. The host acts from the emulator's own clock, so the
// test does not depend on timing.
TEST(EmulatorServer, TellsBytesLostBeforeAHostOpenedThePtyFromThoseLostAfter) {
  const std::string link =
      ::testing::TempDir() + "/emulator_server_pty_" + std::to_string(::getpid());
  int64_t now = 0;
  int readings = 0, host = -1;
  size_t read_bytes = 0;
  const std::function<int64_t()> clock = [&] {
    if (++readings == 2000) {
      host = ::open(link.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK);
      char buf[65536];
      for (ssize_t n; (n = ::read(host, buf, sizeof buf)) > 0;) read_bytes += size_t(n);
    }
    now += 25000;  // three readings a tick: 75 ms, within real time
    return now;
  };
  ServerOptions options;
  options.pty = true;
  options.tick_us = 0;
  options.duration_s = 100.0;
  options.pty_link = link;
  std::ostringstream info;
  std::atomic<bool> stop{false};
  serveEmulator([](int64_t) { return std::make_unique<StreamingDevice>(); }, options, LinkFaults{},
                clock, stop, info);
  ::close(host);
  ::unlink(link.c_str());
  ASSERT_GT(read_bytes, 0u);
  const std::string said = info.str();
  const Unread u = unreadOf(said);
  // 50 kB (a byte per millisecond) before the read, as many after; the pty holds about 20 kB.
  EXPECT_GT(u.before, 10000u) << said;
  EXPECT_GT(u.after, 10000u) << said;
  EXPECT_EQ(u.total, u.before + u.after);
  EXPECT_LE(read_bytes + u.total, 100000u);  // of the 100 s's bytes: read, lost or still queued
}

}  // namespace
}  // namespace sweepmap
