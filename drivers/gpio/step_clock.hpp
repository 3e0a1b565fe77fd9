// The clock the step generator runs on: CLOCK_MONOTONIC with absolute-time sleeps that a new
// command can cut short. Injectable, so tests run the generator on a virtual clock and
// compute every step time exactly.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace sweepmap {

class StepClock {
 public:
  virtual ~StepClock() = default;
  virtual int64_t nowNs() = 0;  // CLOCK_MONOTONIC [ns]
  // Sleeps until the absolute time `deadline_ns`; returns false early if interrupt() was
  // called since the last sleep began (and clears that).
  virtual bool sleepUntilNs(int64_t deadline_ns) = 0;
  virtual void interrupt() = 0;
};

// The host's CLOCK_MONOTONIC. A sleep is a condition-variable wait with an absolute
// steady_clock deadline (pthread_cond_clockwait on CLOCK_MONOTONIC), so interrupt() wakes it;
// it wakes kSpinNs early and spins to the deadline, as a wake-up comes 20-50 us late here even
// at SCHED_FIFO (sweepmap bench: a step's median lateness 6-21 us with 20 us of spin, 0.3-0.5
// us with 60 us), at the price of kSpinNs of CPU per step (0.6 % of a core at mode 7's 100
// steps/s, about 10 % at mode 1's 1600). Short waits (a step pulse) are spun whole.
class MonotonicClock : public StepClock {
 public:
  static constexpr int64_t kSpinNs = 60'000;
  int64_t nowNs() override;
  bool sleepUntilNs(int64_t deadline_ns) override;
  void interrupt() override;

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool interrupted_ = false;
};

int64_t monotonicNowNs();

// Tests: time passes only by sleeping (or advanceTo); every sleep reaches its deadline.
class VirtualClock : public StepClock {
 public:
  explicit VirtualClock(int64_t start_ns) : now_ns_(start_ns) {}
  int64_t nowNs() override { return now_ns_; }
  bool sleepUntilNs(int64_t deadline_ns) override;
  void interrupt() override {}
  void advanceTo(int64_t t_ns);

 private:
  int64_t now_ns_;
};

}  // namespace sweepmap
