#include "sim/stepper.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/angles.hpp"
#include "devices/motion_profile.hpp"

namespace sweepmap {
namespace {

constexpr double kSheetRad = M_PI / 2;  // the shading sheet spans 90 deg

// Uniform in [0, 1), the same on every platform.
double uniform01(std::mt19937_64& g) { return double(g() >> 11) * 0x1.0p-53; }

}  // namespace

SimStepper::SimStepper(const MotorConfig& motor, const SimRigConfig& sim, uint64_t seed,
                       double initial_angle_rad, int64_t start_utime,
                       std::function<void(const ShaftSegment&)> on_truth)
    : sim_(sim),
      home_rad_(motor.home_angle_deg * kDegToRad),
      hysteresis_rad_(sim.switch_hysteresis_deg * kDegToRad),
      motion_rng_(seed),
      switch_rng_(motion_rng_()),
      on_truth_(std::move(on_truth)),
      earliest_command_utime_(start_utime),
      scanned_utime_(start_utime),
      last_report_utime_(start_utime) {
  if (!(sim.start_delay_max_ms >= 0.0)) {
    throw std::invalid_argument("sim.start_delay_max_ms must be >= 0");
  }
  if (!(sim.accel_jitter >= 0.0 && sim.accel_jitter < 1.0)) {
    throw std::invalid_argument("sim.accel_jitter must be in [0, 1)");
  }
  if (!(sim.switch_hysteresis_deg >= 0.0 && sim.switch_hysteresis_deg < 90.0)) {
    throw std::invalid_argument("sim.switch_hysteresis_deg must be in [0, 90)");
  }
  if (!(sim.switch_response_jitter_ms >= 0.0 &&
        sim.switch_response_jitter_ms <= sim.switch_response_ms)) {
    throw std::invalid_argument(
        "sim.switch_response_jitter_ms must be in [0, sim.switch_response_ms]");
  }
  if (!std::isfinite(initial_angle_rad)) {
    throw std::invalid_argument("initial shaft angle must be finite");
  }

  const double rel = wrapAngle(initial_angle_rad - home_rad_);
  true_blocked_ = rel > -kSheetRad && rel <= 0.0;
  if (true_blocked_) {  // band = sheet grown by h/2 at both ends
    band_upper_rad_ =
        home_rad_ + hysteresis_rad_ / 2 +
        2 * M_PI * std::ceil((initial_angle_rad - home_rad_ - hysteresis_rad_ / 2) / (2 * M_PI));
    band_lower_rad_ = band_upper_rad_ - (kSheetRad + hysteresis_rad_);
  } else {  // band = complement of the sheet shrunk by h/2 at both ends
    band_lower_rad_ =
        home_rad_ - hysteresis_rad_ / 2 +
        2 * M_PI * std::floor((initial_angle_rad - home_rad_ + hysteresis_rad_ / 2) / (2 * M_PI));
    band_upper_rad_ = band_lower_rad_ + (2 * M_PI - kSheetRad + hysteresis_rad_);
  }
  reported_blocked_ = true_blocked_;
  emit({start_utime, initial_angle_rad, 0.0, 0.0});
}

void SimStepper::emit(const ShaftSegment& s) {
  trajectory_.apply(s);
  if (on_truth_) on_truth_(s);
}

void SimStepper::command(int64_t now_utime, const StepperCommand& cmd) {
  checkStepperCommand(cmd);

  const int64_t delay_us = std::llround(sim_.start_delay_max_ms * 1000.0 * uniform01(motion_rng_));
  const double accel =
      cmd.accel_rad_s2 * (1.0 + sim_.accel_jitter * (2.0 * uniform01(motion_rng_) - 1.0));
  const int64_t effective_utime = std::max(now_utime + delay_us, earliest_command_utime_);
  earliest_command_utime_ = effective_utime;

  for (const ShaftSegment& s : planMotion(trajectory_, effective_utime, cmd, accel).segments) {
    emit(s);
  }
}

std::vector<SwitchEdge> SimStepper::poll(int64_t now_utime) {
  if (now_utime > scanned_utime_) {
    findCrossings(scanned_utime_, now_utime);
    scanned_utime_ = now_utime;
    earliest_command_utime_ = std::max(earliest_command_utime_, now_utime);
  }
  std::vector<SwitchEdge> reported;
  while (!pending_.empty() && pending_.front().utime <= now_utime) {
    reported_blocked_ = pending_.front().blocked;
    reported.push_back(pending_.front());
    pending_.pop_front();
  }
  return reported;
}

void SimStepper::findCrossings(int64_t from_utime, int64_t to_utime) {
  int64_t from_ns = from_utime * 1000;
  while (const auto c = trajectory_.firstCrossing(from_ns, to_utime * 1000, band_lower_rad_,
                                                  band_upper_rad_)) {
    toggle(c->utime(), c->up);
    from_ns = c->ns();
  }
}

void SimStepper::toggle(double crossing_utime, bool moving_up) {
  true_blocked_ = !true_blocked_;
  // The new band starts h beyond the crossed end (hysteresis) and spans the sheet grown by
  // h (blocked) or its complement grown by h (clear).
  const double width = (true_blocked_ ? kSheetRad : 2 * M_PI - kSheetRad) + hysteresis_rad_;
  if (moving_up) {
    band_lower_rad_ = band_upper_rad_ - hysteresis_rad_;
    band_upper_rad_ = band_lower_rad_ + width;
  } else {
    band_upper_rad_ = band_lower_rad_ + hysteresis_rad_;
    band_lower_rad_ = band_upper_rad_ - width;
  }
  const double response_ms = sim_.switch_response_ms +
                             sim_.switch_response_jitter_ms * (2.0 * uniform01(switch_rng_) - 1.0);
  // A switch cannot report its edges out of order.
  last_report_utime_ =
      std::max<int64_t>(last_report_utime_, std::llround(crossing_utime + response_ms * 1000.0));
  pending_.push_back({last_report_utime_, true_blocked_});
}

}  // namespace sweepmap
