// Turns the planned shaft motion into STEP/DIR pulses on a monotonic clock.
//
// The plan is a ShaftTrajectory of constant-acceleration segments made by planMotion from
// the StepperCommands (devices/motion_profile.hpp): the generator does not re-derive the
// kinematics, it solves for the times at which the planned angle crosses the step angles.
// With step angle d = 2 pi / (steps_per_rev * microsteps), position p (steps from the start,
// where the angle was 0) moves to p + 1 when the planned angle rises through (p + 1) d and
// to p - 1 when it falls through (p - 1) d: step k is emitted when the plan crosses k d, so a
// move by N d emits exactly N steps, and the shaft is never more than one step behind the
// plan. Step levels are taken 1e-12 rad inside, so a move that ends exactly on a step angle
// (reached with zero speed) still makes its last step (< 1 us early).
//
// Pulses: DIR is set as soon as the next step's direction is known (right after the
// previous pulse or at the command), and a step waits until DIR has been stable for
// dir_setup_ns; STEP is high for step_pulse_ns and then low for at least as long.
//
// Time: the plan is in utime [us]; the clock is CLOCK_MONOTONIC [ns];
// utime * 1000 = clock ns + utime_ns_minus_clock_ns. A dedicated thread (start()) sleeps to
// absolute deadlines and is woken by a new command; where permitted it runs SCHED_FIFO
// (silently normal priority otherwise). Without the thread, runUntil() does the same work on
// the caller's thread, which with a VirtualClock makes every step time exact (tests).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <thread>

#include "devices/shaft_trajectory.hpp"
#include "devices/stepper_device.hpp"
#include "drivers/gpio/gpio_backend.hpp"
#include "drivers/gpio/priority_inheritance_mutex.hpp"
#include "drivers/gpio/step_clock.hpp"

namespace sweepmap {

struct StepOutputs {
  int step = -1;  // line offsets
  int dir = -1;
  bool dir_positive_high = true;
};

struct StepTiming {
  // A4988: 1 us high / 1 us low, DIR setup 200 ns; DRV8825: 1.9 us / 1.9 us, 650 ns;
  // TB6600 (optocoupled): 2.5 us / 5 us. 5 us covers them all.
  int64_t step_pulse_ns = 5'000;
  int64_t dir_setup_ns = 5'000;
};

// One emitted step, for the bench: when the plan wanted it and when STEP went high (clock ns).
struct StepRecord {
  int64_t planned_ns = 0;
  int64_t emitted_ns = 0;
  int direction = 0;  // +1 / -1
};

class StepGenerator {
 public:
  // The outputs must be requested already (DIR at the positive level). The shaft stands at
  // angle 0 from start_utime.
  StepGenerator(GpioBackend& gpio, const StepOutputs& lines, const StepTiming& timing,
                StepClock& clock, double step_rad, int64_t start_utime,
                int64_t utime_ns_minus_clock_ns);
  ~StepGenerator();
  StepGenerator(const StepGenerator&) = delete;
  StepGenerator& operator=(const StepGenerator&) = delete;

  // Plans `cmd` from the planned state at now_utime, or at the last emitted step if that is
  // later (steps already made are never re-planned), and wakes the thread. Throws
  // std::invalid_argument for a command checkStepperCommand rejects.
  void command(int64_t now_utime, const StepperCommand& cmd);
  // Without the thread: emits every step due up to until_utime and leaves the clock there.
  void runUntil(int64_t until_utime);
  // The dedicated thread; stop() joins it (also done by the destructor).
  void start(int realtime_priority);
  void stop();

  bool realtime() const { return realtime_; }
  // CPU time the thread has used so far [s] (0 without the thread).
  double threadCpuSeconds() const;
  // Why the thread stopped on its own (a GPIO write failed); empty while it is fine.
  std::string fault() const;
  int64_t position() const;            // steps, signed
  ShaftTrajectory trajectory() const;  // the plan (older than 10 min pruned)
  // Before start(): called for every step made, on the thread that makes it.
  void setOnStep(std::function<void(const StepRecord&)> on_step) { on_step_ = std::move(on_step); }

 private:
  struct NextStep {
    int64_t t_ns = 0;  // plan time, ns (= utime * 1000)
    int direction = 0;
    uint64_t version = 0;  // of the plan it was found in
  };
  std::optional<NextStep> findNext();  // after the last step, in the current plan
  // Sets DIR for `next` if needed; false when the plan changed meanwhile.
  void prepareDirection(const NextStep& next);
  // Marks `next` as made (false if the plan changed since it was found), then pulses STEP.
  bool emit(const NextStep& next);
  void loop();
  int64_t toClock(int64_t plan_ns) const { return plan_ns - offset_ns_; }

  GpioBackend& gpio_;
  StepOutputs lines_;
  StepTiming timing_;
  StepClock& clock_;
  double step_rad_;
  int64_t offset_ns_;
  std::function<void(const StepRecord&)> on_step_;

  mutable PriorityInheritanceMutex mutex_;  // guards the plan, the position, committed_ns_, fault_
  ShaftTrajectory plan_;
  uint64_t version_ = 0;
  int64_t position_ = 0;
  int64_t committed_ns_;  // plan ns up to which steps are made (commands start no earlier)

  // Generator side only.
  int direction_ = 1;          // DIR as set
  int64_t dir_set_clock_ns_;   // when DIR was last changed
  int64_t step_low_clock_ns_;  // when STEP last went low

  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::atomic<bool> realtime_{false};
  std::atomic<bool> faulted_{false};  // fault_ is set (read without the lock on every poll)
  std::string fault_;
};

}  // namespace sweepmap
