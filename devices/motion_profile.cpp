#include "devices/motion_profile.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sweepmap {
namespace {

// Builds the contiguous segments of one command, boundaries on whole microseconds.
class Planner {
 public:
  Planner(int64_t utime, double angle_rad, double velocity_rad_s)
      : utime_(utime), angle_rad_(angle_rad), velocity_rad_s_(velocity_rad_s) {}

  // Ramps to `target_rad_s` at about `accel_rad_s2` (> 0).
  void rampTo(double target_rad_s, double accel_rad_s2) {
    if (target_rad_s == velocity_rad_s_) return;
    const double dv = target_rad_s - velocity_rad_s_;
    const int64_t duration_us =
        std::max<int64_t>(1, std::llround(std::abs(dv) / accel_rad_s2 * 1e6));
    add(duration_us, dv / (double(duration_us) * 1e-6));
    velocity_rad_s_ = target_rad_s;
  }

  // From standstill, turns exactly `delta_rad`: trapezoid (or triangle) at about
  // `max_speed_rad_s` and `accel_rad_s2`, ending at standstill.
  void moveBy(double delta_rad, double max_speed_rad_s, double accel_rad_s2) {
    const double distance = std::abs(delta_rad);
    if (distance == 0.0) return;
    double ramp_s = max_speed_rad_s / accel_rad_s2;
    double cruise_s = distance / max_speed_rad_s - ramp_s;
    if (cruise_s < 0.0) {  // never reaches max speed: triangle
      ramp_s = std::sqrt(distance / accel_rad_s2);
      cruise_s = 0.0;
    }
    const int64_t ramp_us = std::max<int64_t>(1, std::llround(ramp_s * 1e6));
    const int64_t cruise_us = std::llround(cruise_s * 1e6);
    // Peak speed that covers `distance` exactly with the rounded durations.
    const double peak_rad_s = distance / (double(ramp_us + cruise_us) * 1e-6);
    const double accel = std::copysign(peak_rad_s / (double(ramp_us) * 1e-6), delta_rad);
    const double start_rad = angle_rad_;
    add(ramp_us, accel);
    velocity_rad_s_ = std::copysign(peak_rad_s, delta_rad);
    if (cruise_us > 0) add(cruise_us, 0.0);
    add(ramp_us, -accel);
    velocity_rad_s_ = 0.0;
    angle_rad_ = start_rad + delta_rad;
  }

  // Closes the plan: constant velocity from here on.
  std::vector<ShaftSegment> finish() {
    segments_.push_back({utime_, angle_rad_, velocity_rad_s_, 0.0});
    return std::move(segments_);
  }

 private:
  void add(int64_t duration_us, double accel_rad_s2) {
    segments_.push_back({utime_, angle_rad_, velocity_rad_s_, accel_rad_s2});
    const double dt_s = double(duration_us) * 1e-6;
    angle_rad_ += dt_s * (velocity_rad_s_ + 0.5 * accel_rad_s2 * dt_s);
    velocity_rad_s_ += accel_rad_s2 * dt_s;
    utime_ += duration_us;
  }

  int64_t utime_;
  double angle_rad_;
  double velocity_rad_s_;
  std::vector<ShaftSegment> segments_;
};

}  // namespace

void checkStepperCommand(const StepperCommand& cmd) {
  if (!(std::isfinite(cmd.accel_rad_s2) && cmd.accel_rad_s2 > 0.0)) {
    throw std::invalid_argument("stepper command: accel_rad_s2 must be finite and > 0");
  }
  if (!std::isfinite(cmd.velocity_rad_s) || !std::isfinite(cmd.delta_rad)) {
    throw std::invalid_argument("stepper command: velocity and delta must be finite");
  }
  if (cmd.kind == StepperCommand::Kind::kMoveBy && !(cmd.velocity_rad_s > 0.0)) {
    throw std::invalid_argument("stepper command: kMoveBy needs velocity_rad_s > 0");
  }
}

PlannedMotion planMotion(const ShaftTrajectory& current, int64_t start_utime,
                         const StepperCommand& cmd, double accel) {
  if (!(accel > 0.0) || !std::isfinite(accel)) throw std::invalid_argument("accel must be > 0");
  if (!std::isfinite(cmd.velocity_rad_s) || !std::isfinite(cmd.delta_rad)) {
    throw std::invalid_argument("velocity and delta must be finite");
  }
  const double angle0 = current.empty() ? 0.0 : current.angleAt(start_utime);
  const double v0 = current.empty() ? 0.0 : current.velocityAt(start_utime);
  Planner plan(start_utime, angle0, v0);
  switch (cmd.kind) {
    case StepperCommand::Kind::kRun:
      plan.rampTo(cmd.velocity_rad_s, accel);
      break;
    case StepperCommand::Kind::kStop:
      plan.rampTo(0.0, accel);
      break;
    case StepperCommand::Kind::kMoveBy:
      if (!(cmd.velocity_rad_s > 0.0)) throw std::invalid_argument("move needs a speed > 0");
      plan.rampTo(0.0, accel);
      plan.moveBy(cmd.delta_rad, cmd.velocity_rad_s, accel);
      break;
  }
  PlannedMotion out;
  out.segments = plan.finish();
  out.end_utime = out.segments.back().start_utime;
  return out;
}

}  // namespace sweepmap
