// The emulator's link (tools/emulate/emulator_server.hpp) on its own clock: what it says when
// it cannot keep real time.
#include "tools/emulate/emulator_server.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <sstream>
#include <string>

namespace sweepmap {
namespace {

// Streams a few bytes on every advance, as a scanning lidar does.
class StreamingDevice : public EmulatedLidar {
 public:
  void receive(const uint8_t*, size_t, int64_t, std::string*) override {}
  void advance(int64_t, std::string* out) override { out->append(4096, '\x55'); }
  void reset(int64_t) override {}
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

TEST(EmulatorServer, SaysWhenItFellBehindRealTime) {
  const std::string said = serveWithClock(5000, 200, 1500000, 3.0);
  EXPECT_NE(said.find("emulator: serial device at "), std::string::npos) << said;
  // The stall and the clock's step after it: 1.5 s and a bit.
  EXPECT_NE(said.find("emulator: could not keep real time: stalled 1 time, for up to 1.5"),
            std::string::npos)
      << said;
  // Nobody reads the pty: the burst overflows its buffer, and the report counts what was lost.
  EXPECT_NE(said.find("bytes lost since the last report"), std::string::npos) << said;
}

TEST(EmulatorServer, KeepingRealTimeSaysNothingOfIt) {
  const std::string said = serveWithClock(5000, -1, 0, 3.0);
  EXPECT_EQ(said.find("real time"), std::string::npos) << said;
}

}  // namespace
}  // namespace sweepmap
