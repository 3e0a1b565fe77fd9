// Simulated stepper motor with its driver and the photoelectric home switch (rig A).
//
// The controller's command is what it expects; the shaft does something slightly
// different, as in Yuan 2021 section 2:
//  - every command takes effect U(0, sim.start_delay_max_ms) after it is issued (commands
//    still execute in the order issued, and never rewrite motion already seen by poll());
//  - each command's ramps use accel * (1 + U(-sim.accel_jitter, +sim.accel_jitter));
//  - the switch reports its edges sim.switch_response_ms +- U(jitter) after the crossing.
// Steps are exact: a kMoveBy turns exactly delta_rad. Segment boundaries fall on whole
// microseconds; ramp accelerations (and a move's peak speed) are adjusted by the rounding
// (< 1 us per phase) so that velocity and angle stay continuous.
//
// Shaft angles are in the rig frame O, about Z (up), unwrapped.
//
// Home switch: the shading sheet covers the shaft angles (edge - 90 deg, edge], wrapped to
// (-180, 180] deg, where edge = motor.home_angle_deg + h/2 while the shaft turns in the
// positive direction and home_angle_deg - h/2 while it turns negative
// (h = sim.switch_hysteresis_deg). So at the home edge the sheet enters the beam (turning
// negative) at home - h/2 and leaves it (turning positive) at home + h/2; at the far end
// (90 deg below) likewise shifted by h/2 along the motion. A reversal inside the band
// changes nothing (Schmitt trigger). The level at construction uses h = 0.
//
// Randomness: one std::mt19937_64(seed). Its first draw seeds the switch's own generator,
// so the motion does not depend on how often poll() is called; each command then draws
// its start delay, then its acceleration factor; each edge draws its response jitter.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <random>
#include <vector>

#include "core/rig_components.hpp"
#include "devices/shaft_trajectory.hpp"
#include "devices/stepper_device.hpp"

namespace sweepmap {

class SimStepper : public StepperDevice {
 public:
  // The shaft stands still at initial_angle_rad from start_utime; that segment is passed to
  // on_truth (may be empty) before the constructor returns, and every later segment when
  // the command that plans it is issued. Throws std::invalid_argument for an error model
  // outside its domain (negative times, accel_jitter outside [0, 1), hysteresis outside
  // [0, 90) deg, response jitter larger than the response time).
  SimStepper(const MotorConfig& motor, const SimRigConfig& sim, uint64_t seed,
             double initial_angle_rad, int64_t start_utime,
             std::function<void(const ShaftSegment&)> on_truth);

  // Throws std::invalid_argument for a non-finite or non-positive accel, a non-positive
  // kMoveBy speed, or non-finite values.
  void command(int64_t now_utime, const StepperCommand& cmd) override;
  std::vector<SwitchEdge> poll(int64_t now_utime) override;
  bool switchBlocked() const override { return reported_blocked_; }

  // The true motion so far and as planned; it is never pruned here.
  const ShaftTrajectory& trajectory() const { return trajectory_; }

 private:
  void emit(const ShaftSegment& s);
  // Finds the true switch crossings in [from_utime, to_utime] and queues their reports.
  void findCrossings(int64_t from_utime, int64_t to_utime);
  // Flips the true level at `crossing_utime` after the shaft left the band through its
  // upper (moving_up) or lower end, and queues the report.
  void toggle(double crossing_utime, bool moving_up);

  SimRigConfig sim_;
  double home_rad_;
  double hysteresis_rad_;
  std::mt19937_64 motion_rng_;
  std::mt19937_64 switch_rng_;
  std::function<void(const ShaftSegment&)> on_truth_;
  ShaftTrajectory trajectory_;
  int64_t earliest_command_utime_;  // commands take effect no earlier than this
  int64_t scanned_utime_;           // switch crossings are known up to here

  // True switch state: the level changes when the unwrapped shaft angle leaves
  // (band_lower_rad_, band_upper_rad_].
  bool true_blocked_;
  double band_lower_rad_;
  double band_upper_rad_;

  std::deque<SwitchEdge> pending_;  // found, not yet reported; report times non-decreasing
  int64_t last_report_utime_;
  bool reported_blocked_;
};

}  // namespace sweepmap
