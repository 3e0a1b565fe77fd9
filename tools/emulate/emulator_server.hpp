// Serves an emulated lidar (an EmulatedLidar protocol engine fed by the simulated world)
// over a real transport: a loopback TCP server (one client at a time, as the UST-10LX) or a
// pseudo-terminal (as a USB serial adapter). Fault injection works on the bytes and the
// link: corrupted bytes at a rate, a stall (the device sends nothing for a while: the
// bytes are lost, as from a UART nobody reads), and a hang-up (the connection dropped, the
// pty closed and its path gone) after which the device comes back, powered up afresh.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <ostream>
#include <random>
#include <string>

#include "tools/emulate/emulated_lidar.hpp"

namespace sweepmap {

struct LinkFaults {
  double corrupt_rate = 0.0;  // probability per sent byte of one flipped bit
  double stall_at_s = -1.0;   // after this many seconds of serving (< 0: never) ...
  double stall_s = 0.0;       // ... send nothing for this long
  double hangup_at_s = -1.0;  // after this many seconds (< 0: never) drop the link ...
  double down_s = 1.0;        // ... and be gone this long, then come back powered up afresh
  uint64_t seed = 1;
};

struct ServerOptions {
  // TCP: "HOST:PORT" to listen on (loopback addresses only: 127.0.0.0/8 or ::1).
  std::string listen;
  // PTY: a path to keep a symlink to the current pty's slave at ("" = only print the
  // slave's path). A hang-up removes the link; the new pty gets the same link.
  bool pty = false;
  std::string pty_link;
  int tick_us = 1000;     // how often the device model advances
  double duration_s = 0;  // stop after this long (0 = until stop is set)
};

// Runs until `stop` (or the duration). `make_device` builds the engine at power-up (again
// after each hang-up); `now_us` is the emulator clock. Prints the address or pty path to
// `info` as soon as a host can open it. Throws std::runtime_error for a bad address or a
// failure to listen / create the pty.
void serveEmulator(const std::function<std::unique_ptr<EmulatedLidar>(int64_t now_us)>& make_device,
                   const ServerOptions& options, const LinkFaults& faults,
                   const std::function<int64_t()>& now_us, const std::atomic<bool>& stop,
                   std::ostream& info);

}  // namespace sweepmap
