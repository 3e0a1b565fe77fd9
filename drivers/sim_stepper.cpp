#include "drivers/sim_stepper.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>

#include "core/angles.hpp"
#include "drivers/motion_profile.hpp"

namespace sweepmap {
namespace {

constexpr double kSheetRad = M_PI / 2;  // the shading sheet spans 90 deg
// Roots this close outside a piece still count (clamped), so that a crossing exactly at a
// segment boundary is not lost to rounding on both sides; much finer than the 1 us clock.
constexpr double kRootSlackS = 1e-9;

// Uniform in [0, 1), the same on every platform.
double uniform01(std::mt19937_64& g) { return double(g() >> 11) * 0x1.0p-53; }

// Earliest tau in [from_s, to_s] (give or take kRootSlackS) at which
// angle0 + v*tau + a*tau^2/2 crosses `level` upward (up = true) or downward.
std::optional<double> firstCrossing(double angle0, double v, double a, double level, bool up,
                                    double from_s, double to_s) {
  std::array<double, 2> roots{};
  size_t n = 0;
  const double c = angle0 - level;
  if (a == 0.0) {
    if (v != 0.0) roots[n++] = -c / v;
  } else {
    const double disc = v * v - 2.0 * a * c;
    if (disc < 0.0) return std::nullopt;
    // Numerically stable roots of (a/2) tau^2 + v tau + c.
    const double q = -0.5 * (v + std::copysign(std::sqrt(disc), v));
    if (q != 0.0) {
      roots[n++] = q / (0.5 * a);
      roots[n++] = c / q;
    } else {
      roots[n++] = 0.0;  // v = 0 and c = 0
    }
    if (n == 2 && roots[1] < roots[0]) std::swap(roots[0], roots[1]);
  }
  for (size_t i = 0; i < n; ++i) {
    const double tau = roots[i];
    if (tau < from_s - kRootSlackS || tau > to_s + kRootSlackS) continue;
    const double slope = v + a * tau;
    const double direction = slope != 0.0 ? slope : a;  // touching at rest: where it goes next
    if (up ? direction > 0.0 : direction < 0.0) return std::clamp(tau, from_s, to_s);
  }
  return std::nullopt;
}

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
  if (!(std::isfinite(cmd.accel_rad_s2) && cmd.accel_rad_s2 > 0.0)) {
    throw std::invalid_argument("stepper command: accel_rad_s2 must be finite and > 0");
  }
  if (!std::isfinite(cmd.velocity_rad_s) || !std::isfinite(cmd.delta_rad)) {
    throw std::invalid_argument("stepper command: velocity and delta must be finite");
  }
  if (cmd.kind == StepperCommand::Kind::kMoveBy && !(cmd.velocity_rad_s > 0.0)) {
    throw std::invalid_argument("stepper command: kMoveBy needs velocity_rad_s > 0");
  }

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
  const auto& segs = trajectory_.segments();
  auto it = std::upper_bound(segs.begin(), segs.end(), from_utime,
                             [](int64_t t, const ShaftSegment& s) { return t < s.start_utime; });
  if (it != segs.begin()) --it;
  for (; it != segs.end() && it->start_utime <= to_utime; ++it) {
    const auto next = std::next(it);
    const int64_t piece_end = next == segs.end() ? to_utime : std::min(next->start_utime, to_utime);
    const int64_t piece_start = std::max(it->start_utime, from_utime);
    if (piece_end < piece_start) continue;
    // Times relative to the segment's start [s].
    double tau_s = double(piece_start - it->start_utime) * 1e-6;
    const double end_s = double(piece_end - it->start_utime) * 1e-6;
    for (;;) {
      const auto up = firstCrossing(it->angle_rad, it->velocity_rad_s, it->accel_rad_s2,
                                    band_upper_rad_, true, tau_s, end_s);
      const auto down = firstCrossing(it->angle_rad, it->velocity_rad_s, it->accel_rad_s2,
                                      band_lower_rad_, false, tau_s, end_s);
      if (!up && !down) break;
      const bool moving_up = up && (!down || *up <= *down);
      tau_s = moving_up ? *up : *down;
      toggle(double(it->start_utime) + tau_s * 1e6, moving_up);
    }
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
