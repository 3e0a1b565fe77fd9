#include "drivers/motion_profile.hpp"

#include <cmath>
#include <stdexcept>

namespace sweepmap {
namespace {

int64_t toUs(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e6)); }

// Appends a ramp from the last segment's state to `v_target`; returns its end time.
int64_t appendRamp(std::vector<ShaftSegment>* segs, int64_t t0, double angle0, double v0,
                   double v_target, double accel, double* angle_end) {
  const double dv = v_target - v0;
  if (dv == 0.0) {
    segs->push_back({t0, angle0, v0, 0.0});
    *angle_end = angle0;
    return t0;
  }
  const double a = std::copysign(accel, dv);
  const int64_t dt_us = toUs(std::abs(dv) / accel);
  const double dt = 1e-6 * static_cast<double>(dt_us);
  segs->push_back({t0, angle0, v0, a});
  *angle_end = angle0 + v0 * dt + 0.5 * a * dt * dt;
  segs->push_back({t0 + dt_us, *angle_end, v_target, 0.0});
  return t0 + dt_us;
}

}  // namespace

PlannedMotion planMotion(const ShaftTrajectory& current, int64_t t0, const StepperCommand& cmd,
                         double accel) {
  if (!(accel > 0.0) || !std::isfinite(accel)) throw std::invalid_argument("accel must be > 0");
  PlannedMotion plan;
  const double angle0 = current.empty() ? 0.0 : current.angleAt(t0);
  const double v0 = current.empty() ? 0.0 : current.velocityAt(t0);
  double angle = angle0;
  switch (cmd.kind) {
    case StepperCommand::Kind::kRun:
    case StepperCommand::Kind::kStop: {
      const double v = cmd.kind == StepperCommand::Kind::kRun ? cmd.velocity_rad_s : 0.0;
      if (!std::isfinite(v)) throw std::invalid_argument("velocity must be finite");
      plan.end_utime = appendRamp(&plan.segments, t0, angle0, v0, v, accel, &angle);
      break;
    }
    case StepperCommand::Kind::kMoveBy: {
      const double vmax = cmd.velocity_rad_s;
      if (!(vmax > 0.0) || !std::isfinite(cmd.delta_rad)) {
        throw std::invalid_argument("move needs a positive speed and a finite delta");
      }
      // Come to rest first, then a trapezoid (triangle when short) over exactly delta.
      int64_t t = t0;
      if (v0 != 0.0) {
        t = appendRamp(&plan.segments, t0, angle0, v0, 0.0, accel, &angle);
        plan.segments.pop_back();  // the hold at rest is replaced by the move
      }
      const double start = angle;
      const double d = std::abs(cmd.delta_rad);
      const double s = cmd.delta_rad >= 0 ? 1.0 : -1.0;
      const double v_peak = std::min(vmax, std::sqrt(d * accel));
      const int64_t ramp_us = toUs(v_peak / accel);
      const double ramp = 1e-6 * static_cast<double>(ramp_us);
      const double ramp_dist = 0.5 * accel * ramp * ramp;
      const int64_t cruise_us = v_peak > 0 ? toUs(std::max(0.0, d - 2.0 * ramp_dist) / v_peak) : 0;
      const double cruise = 1e-6 * static_cast<double>(cruise_us);
      if (ramp_us > 0) {
        plan.segments.push_back({t, start, 0.0, s * accel});
        plan.segments.push_back({t + ramp_us, start + s * ramp_dist, s * v_peak, 0.0});
        plan.segments.push_back({t + ramp_us + cruise_us,
                                 start + s * (ramp_dist + v_peak * cruise), s * v_peak,
                                 -s * accel});
      }
      // Steps are exact: the move ends at start + delta (microsecond rounding of the
      // phase times leaves a sub-microradian step here).
      const int64_t end = t + 2 * ramp_us + cruise_us;
      plan.segments.push_back({end, start + cmd.delta_rad, 0.0, 0.0});
      plan.end_utime = end;
      break;
    }
  }
  return plan;
}

}  // namespace sweepmap
