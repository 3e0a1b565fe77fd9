#include "drivers/gpio/step_generator.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

#include <algorithm>
#include <ctime>
#include <limits>
#include <mutex>

#include "devices/motion_profile.hpp"

namespace sweepmap {
namespace {

// Step levels sit this far inside, so a move ending exactly on a step angle makes that step.
constexpr double kLevelSlackRad = 1e-12;
constexpr int64_t kKeepPlanUs = 600'000'000;
constexpr int64_t kIdleWaitNs = 1'000'000'000;  // no step planned: wait for a command
constexpr int64_t kLongAgoNs = std::numeric_limits<int64_t>::min() / 4;

}  // namespace

StepGenerator::StepGenerator(GpioBackend& gpio, const StepOutputs& lines, const StepTiming& timing,
                             StepClock& clock, double step_rad, int64_t start_utime,
                             int64_t utime_ns_minus_clock_ns)
    : gpio_(gpio),
      lines_(lines),
      timing_(timing),
      clock_(clock),
      step_rad_(step_rad),
      offset_ns_(utime_ns_minus_clock_ns),
      committed_ns_(start_utime * 1000),
      dir_set_clock_ns_(kLongAgoNs),
      step_low_clock_ns_(kLongAgoNs) {
  plan_.apply({start_utime, 0.0, 0.0, 0.0});
}

StepGenerator::~StepGenerator() { stop(); }

void StepGenerator::command(int64_t now_utime, const StepperCommand& cmd) {
  checkStepperCommand(cmd);
  {
    std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
    const int64_t start_utime = std::max(now_utime, (committed_ns_ + 999) / 1000);
    const PlannedMotion motion = planMotion(plan_, start_utime, cmd, cmd.accel_rad_s2);
    for (const ShaftSegment& s : motion.segments) plan_.apply(s);
    plan_.pruneBefore(start_utime - kKeepPlanUs);
    ++version_;
  }
  clock_.interrupt();
}

std::optional<StepGenerator::NextStep> StepGenerator::findNext() {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  const double upper = double(position_ + 1) * step_rad_ - kLevelSlackRad;
  const double lower = double(position_ - 1) * step_rad_ + kLevelSlackRad;
  const auto c =
      plan_.firstCrossing(committed_ns_, std::numeric_limits<int64_t>::max(), lower, upper);
  if (!c) return std::nullopt;
  return NextStep{std::max(c->ns(), committed_ns_), c->up ? 1 : -1, version_};
}

void StepGenerator::prepareDirection(const NextStep& next) {
  if (next.direction == direction_) return;
  gpio_.setOutput(lines_.dir, (next.direction > 0) == lines_.dir_positive_high);
  direction_ = next.direction;
  dir_set_clock_ns_ = clock_.nowNs();
}

bool StepGenerator::emit(const NextStep& next) {
  {
    std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
    if (version_ != next.version) return false;
    committed_ns_ = next.t_ns;  // made: a command from now on plans after it
    position_ += next.direction;
  }
  const int64_t due = std::max({toClock(next.t_ns), dir_set_clock_ns_ + timing_.dir_setup_ns,
                                step_low_clock_ns_ + timing_.step_pulse_ns});
  while (!clock_.sleepUntilNs(due)) {
  }
  const int64_t high_ns = clock_.nowNs();
  gpio_.setOutput(lines_.step, true);
  while (!clock_.sleepUntilNs(high_ns + timing_.step_pulse_ns)) {
  }
  gpio_.setOutput(lines_.step, false);
  step_low_clock_ns_ = clock_.nowNs();
  if (on_step_) on_step_({toClock(next.t_ns), high_ns, next.direction});
  return true;
}

void StepGenerator::runUntil(int64_t until_utime) {
  const int64_t until_ns = until_utime * 1000;
  for (;;) {
    const auto next = findNext();
    if (next) prepareDirection(*next);
    if (!next || next->t_ns > until_ns) break;
    clock_.sleepUntilNs(toClock(next->t_ns));
    emit(*next);
  }
  clock_.sleepUntilNs(toClock(until_ns));
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  committed_ns_ = std::max(committed_ns_, until_ns);
}

void StepGenerator::loop() {
  try {
    while (!stopping_) {
      const auto next = findNext();
      if (!next) {
        clock_.sleepUntilNs(clock_.nowNs() + kIdleWaitNs);
        continue;
      }
      prepareDirection(*next);
      if (!clock_.sleepUntilNs(toClock(next->t_ns)) || stopping_) continue;
      emit(*next);
    }
  } catch (const std::exception& e) {
    std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
    fault_ = e.what();
    faulted_ = true;
  }
}

void StepGenerator::start(int realtime_priority) {
  if (thread_.joinable()) return;
  stopping_ = false;
  thread_ = std::thread([this, realtime_priority] {
    sched_param param{};
    param.sched_priority = realtime_priority;
    realtime_ = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);  // wake at the deadline, not 50 us later
    loop();
  });
}

void StepGenerator::stop() {
  if (!thread_.joinable()) return;
  stopping_ = true;
  clock_.interrupt();
  thread_.join();
}

double StepGenerator::threadCpuSeconds() const {
  if (!thread_.joinable()) return 0.0;
  clockid_t cpu_clock{};
  timespec ts{};
  if (pthread_getcpuclockid(const_cast<std::thread&>(thread_).native_handle(), &cpu_clock) != 0 ||
      clock_gettime(cpu_clock, &ts) != 0) {
    return 0.0;
  }
  return double(ts.tv_sec) + double(ts.tv_nsec) * 1e-9;
}

std::string StepGenerator::fault() const {
  if (!faulted_) return {};
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  return fault_;
}

int64_t StepGenerator::position() const {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  return position_;
}

ShaftTrajectory StepGenerator::trajectory() const {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  return plan_;
}

}  // namespace sweepmap
