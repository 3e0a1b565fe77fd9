#include "drivers/gpio/step_clock.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>

namespace sweepmap {

int64_t monotonicNowNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

int64_t MonotonicClock::nowNs() { return monotonicNowNs(); }

bool MonotonicClock::sleepUntilNs(int64_t deadline_ns) {
  // steady_clock is CLOCK_MONOTONIC on Linux (libstdc++), so its epoch is the same.
  const std::chrono::steady_clock::time_point wake{std::chrono::nanoseconds(deadline_ns - kSpinNs)};
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (deadline_ns - monotonicNowNs() > kSpinNs) {
      cv_.wait_until(lock, wake, [&] { return interrupted_; });
    }
    if (interrupted_) {
      interrupted_ = false;
      return false;
    }
  }
  while (monotonicNowNs() < deadline_ns) {
  }
  return true;
}

void MonotonicClock::interrupt() {
  std::lock_guard<std::mutex> lock(mutex_);
  interrupted_ = true;
  cv_.notify_all();
}

bool VirtualClock::sleepUntilNs(int64_t deadline_ns) {
  now_ns_ = std::max(now_ns_, deadline_ns);
  return true;
}

void VirtualClock::advanceTo(int64_t t_ns) { now_ns_ = std::max(now_ns_, t_ns); }

}  // namespace sweepmap
