// Planning of stepper motions as constant-acceleration segments. Shared by the motor
// controller (its open-loop model of what it commanded) and the simulated stepper (the
// true motion, with the error sources applied to the command before planning).
#pragma once

#include <cstdint>
#include <vector>

#include "devices/shaft_trajectory.hpp"
#include "devices/stepper_device.hpp"

namespace sweepmap {

struct PlannedMotion {
  std::vector<ShaftSegment> segments;  // in time order, the first starts at the command time
  int64_t end_utime = 0;               // when the commanded state is reached
};

// Throws std::invalid_argument for a non-finite or non-positive accel, a non-positive kMoveBy
// speed, or non-finite values: what a device checks before it executes a command.
void checkStepperCommand(const StepperCommand& cmd);

// Plans `cmd` from the state of `current` at `start_utime`, ramping at about `accel_rad_s2`
// (which overrides cmd.accel_rad_s2, so a simulation can perturb it). Segment boundaries
// fall on whole microseconds; ramp accelerations (and a move's peak speed) absorb the
// rounding so angle and velocity stay continuous and a kMoveBy turns exactly delta_rad.
PlannedMotion planMotion(const ShaftTrajectory& current, int64_t start_utime,
                         const StepperCommand& cmd, double accel_rad_s2);

}  // namespace sweepmap
