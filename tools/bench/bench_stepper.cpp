#include "tools/bench/bench_stepper.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <thread>
#include <vector>

#include "core/angles.hpp"
#include "devices/motion_profile.hpp"
#include "drivers/gpio/fake_gpio_backend.hpp"
#include "drivers/gpio/gpio_stepper.hpp"
#include "tools/bench/proc_stats.hpp"

namespace sweepmap {
namespace {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(q * double(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(i), v.end());
  return v[i];
}

}  // namespace

int benchStepper(const StepperBenchOptions& o, std::ostream& out, StepperBenchResult* result) {
  GpioStepperOptions options;
  options.lines.chip = "fake";
  options.lines.step = 17;
  options.lines.dir = 27;
  options.lines.enable = 22;
  options.lines.home = 23;
  options.steps_per_rev = o.motor.steps_per_rev;
  options.microsteps = o.motor.microsteps;
  options.dedicated_thread = true;
  MonotonicClock clock;
  FakeGpioBackend gpio(clock);
  std::vector<StepRecord> steps;
  steps.reserve(1 << 16);
  // The sweep as the controller commands it: run up to the mode's speed, hold it through the
  // window (and the margins), stop.
  const ScanMode mode = scanMode(7);
  const double omega = o.motor.sweep_angle_deg * kDegToRad / mode.period_s;
  const double accel = o.motor.accel_deg_s2 * kDegToRad;
  const double run_s = omega / accel + 2 * o.motor.margin_s + mode.period_s;
  const auto t0 = BenchClock::now();
  const double cpu0 = cpuSeconds(RUSAGE_SELF);
  double thread_cpu_s = 0;
  bool realtime = false;
  options.on_step = [&steps](const StepRecord& r) {
    if (steps.size() < steps.capacity()) steps.push_back(r);
  };
  {
    const int64_t start_utime = clock.nowNs() / 1000;
    GpioStepper stepper(options, gpio, clock, start_utime);
    stepper.command(start_utime + 1000, {StepperCommand::Kind::kRun, omega, accel, 0.0});
    const auto poll_until = [&](double seconds) {
      const auto end = BenchClock::now() + std::chrono::duration<double>(seconds);
      while (BenchClock::now() < end) {
        stepper.poll(clock.nowNs() / 1000);
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    };
    poll_until(run_s);
    stepper.command(clock.nowNs() / 1000, {StepperCommand::Kind::kStop, 0.0, accel, 0.0});
    poll_until(omega / accel + 0.2);
    thread_cpu_s = stepper.stepThreadCpuSeconds();
    realtime = stepper.realtime();
  }
  const double wall_s = secondsSince(t0);
  const double process_cpu_s = cpuSeconds(RUSAGE_SELF) - cpu0;
  std::vector<double> late_us;
  late_us.reserve(steps.size());
  for (const StepRecord& r : steps) late_us.push_back(double(r.emitted_ns - r.planned_ns) * 1e-3);
  const auto late_100us =
      std::count_if(late_us.begin(), late_us.end(), [](double l) { return l > 100; });
  out << "  step generator (fake chip, real clock, thread "
      << (realtime ? "SCHED_FIFO" : "normal priority: SCHED_FIFO not permitted") << "), mode-7 "
      << "sweep at " << omega / kDegToRad << " deg/s, " << o.motor.steps_per_rev << " x "
      << o.motor.microsteps << " steps/rev: " << steps.size() << " steps in " << wall_s << " s\n";
  out << "    emitted - planned step time [us]: median " << quantile(late_us, 0.5) << ", p99 "
      << quantile(late_us, 0.99) << ", max " << quantile(late_us, 1.0) << ", min "
      << quantile(late_us, 0.0) << "; " << late_100us << " steps over 100 us late\n";
  out << "    CPU share of the generator thread " << 100.0 * thread_cpu_s / wall_s
      << " % (whole process incl. the 1 kHz poll loop " << 100.0 * process_cpu_s / wall_s
      << " %)\n";
  if (result) result->thread_cpu_share = thread_cpu_s / wall_s;
  return 0;
}

}  // namespace sweepmap
