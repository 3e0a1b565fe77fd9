// Rig A's real stepper and home switch on GPIO lines (motor.device: gpiod://...): a
// StepperDevice the MotorController drives exactly as it drives the SimStepper.
//
// command() plans the StepperCommand from the device's own plan (planMotion, as the
// controller's model does) and hands it to the StepGenerator, which pulses STEP/DIR on a
// monotonic clock. poll() returns the home switch's debounced edges, dated by the kernel's
// timestamp of each transition's first edge and converted to the processes' wall-clock
// utime, so the controller learns when the sheet really crossed the beam.
//
// Safety: ENABLE is requested at its disable level and enabled once every line is held;
// the destructor (a normal stop, SIGINT/SIGTERM through the process's stop path) stops the
// pulses and disables the driver; a fatal signal disables it from the signal handler
// (fatal_signal_guard.hpp). What holds the line when no process drives it is the wiring's
// job (README, "Rig A's stepper and switch on GPIO").
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/device_uri.hpp"
#include "core/rig_components.hpp"
#include "devices/stepper_device.hpp"
#include "drivers/gpio/gpio_backend.hpp"
#include "drivers/gpio/step_clock.hpp"
#include "drivers/gpio/step_generator.hpp"
#include "drivers/gpio/switch_debouncer.hpp"

namespace sweepmap {

struct GpioStepperOptions {
  GpioLines lines;
  int steps_per_rev = 200;
  int microsteps = 16;
  int64_t debounce_ns = 2'000'000;
  StepTiming timing;
  // true: a dedicated (SCHED_FIFO where permitted) thread makes the steps. false: poll()
  // makes the steps due up to its `now` on the caller's thread (tests on a virtual clock).
  bool dedicated_thread = true;
  int realtime_priority = 50;
  // utime * 1000 = clock ns + this (processes/live_runner.hpp wallMinusMonotonicNs()).
  int64_t utime_ns_minus_clock_ns = 0;
  // Called for every step made, on the thread that makes it (the bench's timing).
  std::function<void(const StepRecord&)> on_step;
  double stepRad() const;
};

// The options of motor.device (a gpiod:// URI), motor.steps_per_rev, motor.microsteps and
// motor.switch_debounce_ms. Throws std::invalid_argument when motor.device is not gpiod://.
GpioStepperOptions gpioStepperOptions(const MotorConfig& motor);

class GpioStepper : public StepperDevice {
 public:
  // Requests the lines on `gpio` (throws GpioError naming the chip, line and errno text) and
  // enables the driver. The shaft is taken to stand at angle 0 at start_utime.
  GpioStepper(const GpioStepperOptions& options, GpioBackend& gpio, StepClock& clock,
              int64_t start_utime);
  ~GpioStepper() override;
  GpioStepper(const GpioStepper&) = delete;
  GpioStepper& operator=(const GpioStepper&) = delete;

  void command(int64_t now_utime, const StepperCommand& cmd) override;
  // Throws GpioError if the step thread failed (the driver is disabled then).
  std::vector<SwitchEdge> poll(int64_t now_utime) override;
  bool switchBlocked() const override { return debouncer_.level(); }

  int64_t position() const { return generator_.position(); }  // steps made, signed
  ShaftTrajectory plan() const { return generator_.trajectory(); }
  bool realtime() const { return generator_.realtime(); }
  double stepThreadCpuSeconds() const { return generator_.threadCpuSeconds(); }
  // Why the step thread stopped (a GPIO write failed; the driver is disabled at the next
  // poll); empty while it runs.
  std::string fault() const { return generator_.fault(); }

 private:
  void disable();
  bool blockedAt(bool level_high) const { return level_high == options_.lines.home_blocked_high; }

  GpioStepperOptions options_;
  GpioBackend& gpio_;
  int fatal_slot_ = -1;
  SwitchDebouncer debouncer_;  // in "blocked" terms
  StepGenerator generator_;
};

}  // namespace sweepmap
