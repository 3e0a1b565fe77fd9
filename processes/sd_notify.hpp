// systemd's notification protocol (sd_notify(3)) without libsystemd: a datagram of
// "KEY=VALUE" lines to the AF_UNIX socket named by $NOTIFY_SOCKET (an '@' first means the
// abstract namespace). systemd (Type=notify, WatchdogSec=) and `sweepmap launch` listen on it.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace sweepmap {

// Sends `state` (e.g. "READY=1") to $NOTIFY_SOCKET; false when it is unset or sending failed.
bool sdNotify(const std::string& state);

// The watchdog interval systemd asks for: WATCHDOG_USEC [us] when WATCHDOG_PID is unset or
// this process's pid; 0 when there is no watchdog.
int64_t sdWatchdogUsec();

// What a worker loop tells its supervisor: ready() once it runs, alive() on every turn (it
// sends WATCHDOG=1 when half the watchdog interval has passed since the last one), stopping()
// when it ends. Nothing is sent when there is no $NOTIFY_SOCKET.
class SdNotifier {
 public:
  SdNotifier();
  void ready();
  void alive(std::chrono::steady_clock::time_point now = std::chrono::steady_clock::now());
  void stopping();
  std::chrono::microseconds pingInterval() const { return interval_; }

 private:
  bool enabled_ = false;
  std::chrono::microseconds interval_{0};  // WATCHDOG_USEC / 2; 0 = no watchdog
  std::chrono::steady_clock::time_point last_ping_{};
};

}  // namespace sweepmap
