// Stepper part of `sweepmap bench`: the GPIO step generator on the real clock (its own
// thread, SCHED_FIFO where permitted) driving the fake chip through a sweep of the rig's
// motor in mode 7: how late each step is against its planned time, and the CPU share of the
// generator's thread. Prints figures; asserts nothing.
#pragma once

#include <ostream>

#include "core/rig_components.hpp"

namespace sweepmap {

struct StepperBenchOptions {
  MotorConfig motor;  // steps_per_rev, microsteps, accel; mode 7 is used whatever it says
};

struct StepperBenchResult {
  double thread_cpu_share = 0.0;  // the generator thread's CPU seconds / wall seconds
};

int benchStepper(const StepperBenchOptions& options, std::ostream& out,
                 StepperBenchResult* result = nullptr);

}  // namespace sweepmap
