#include "processes/motor_controller.hpp"

#include <cmath>

#include "core/angles.hpp"
#include "devices/motion_profile.hpp"
#include "processes/channels.hpp"
#include "sweepmap/motor_state_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "sweepmap/switch_event_t.hpp"

namespace sweepmap {
namespace {

constexpr double kHomingApproachRad = 10.0 * kDegToRad;  // re-homing starts this far above the edge

int64_t us(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e6)); }

}  // namespace

const char* phaseName(MotorController::Phase p) {
  switch (p) {
    case MotorController::Phase::kIdle:
      return "idle";
    case MotorController::Phase::kHomingLeave:
      return "homing-leave";
    case MotorController::Phase::kHomingSeek:
      return "homing-seek";
    case MotorController::Phase::kHomingStop:
      return "homing-stop";
    case MotorController::Phase::kPositioning:
      return "positioning";
    case MotorController::Phase::kAccelerating:
      return "accelerating";
    case MotorController::Phase::kScanning:
      return "scanning";
    case MotorController::Phase::kDecelerating:
      return "decelerating";
    case MotorController::Phase::kReturning:
      return "returning";
    case MotorController::Phase::kDone:
      return "done";
    case MotorController::Phase::kFault:
      return "fault";
  }
  return "?";
}

MotorController::MotorController(const RotatingLidarConfig& rig, StepperDevice* device, int sweeps,
                                 int64_t start_utime)
    : Node("motor"), rig_(rig), device_(device), sweeps_wanted_(sweeps) {
  const ScanMode mode = scanMode(rig.motor.mode);
  window_us_ = us(mode.period_s);
  omega_ = rig.motor.sweep_angle_deg * kDegToRad / mode.period_s;  // Eq. 3
  nominal_.apply({start_utime, 0.0, 0.0, 0.0});
}

double MotorController::preRollAngle() const {
  const double a = rig_.motor.accel_deg_s2 * kDegToRad;
  return omega_ * omega_ / (2.0 * a) + omega_ * rig_.motor.margin_s;
}

double MotorController::commandedAngle(int64_t utime) const {
  return nominal_.angleAt(utime) + home_offset_;
}

void MotorController::command(int64_t now, const StepperCommand& cmd) {
  device_->command(now, cmd);
  const PlannedMotion plan = planMotion(nominal_, now, cmd, cmd.accel_rad_s2);
  for (const auto& s : plan.segments) nominal_.apply(s);
  nominal_.pruneBefore(now - 60LL * 1000000);
  motion_end_ = plan.end_utime;
}

void MotorController::moveTo(int64_t now, double angle_rad, double speed_rad_s) {
  StepperCommand c;
  c.kind = StepperCommand::Kind::kMoveBy;
  c.delta_rad = angle_rad - commandedAngle(now);
  c.velocity_rad_s = speed_rad_s;
  c.accel_rad_s2 = rig_.motor.accel_deg_s2 * kDegToRad;
  command(now, c);
}

void MotorController::enter(int64_t now, Phase phase, Outbox& out) {
  phase_ = phase;
  publishState(now, out);
}

void MotorController::fault(int64_t now, const std::string& why, Outbox& out) {
  StepperCommand stop;
  stop.kind = StepperCommand::Kind::kStop;
  stop.accel_rad_s2 = rig_.motor.accel_deg_s2 * kDegToRad;
  command(now, stop);
  detail_ = why;
  setFailed(why);
  enter(now, Phase::kFault, out);
}

void MotorController::startHoming(int64_t now, Outbox& out) {
  const double speed = rig_.motor.homing_speed_deg_s * kDegToRad;
  const double accel = rig_.motor.accel_deg_s2 * kDegToRad;
  if (device_->switchBlocked()) {
    command(now, {StepperCommand::Kind::kRun, speed, accel, 0.0});
    seek_start_ = commandedAngle(now);
    enter(now, Phase::kHomingLeave, out);
  } else {
    command(now, {StepperCommand::Kind::kRun, -speed, accel, 0.0});
    seek_start_ = commandedAngle(now);
    enter(now, Phase::kHomingSeek, out);
  }
}

void MotorController::advance(int64_t now, Outbox& out) {
  handleSwitchEdges(now, out);
  advancePhase(now, out);
  if (now >= next_state_utime_) {
    publishState(now, out);
  }
}

double MotorController::startAngle() const {
  return rig_.motor.action_sequence == "naive" ? 0.0 : -preRollAngle();
}

void MotorController::handleSwitchEdges(int64_t now, Outbox& out) {
  const double accel = rig_.motor.accel_deg_s2 * kDegToRad;
  const int64_t settle = us(rig_.motor.settle_s);
  for (const SwitchEdge& e : device_->poll(now)) {
    switch_event_t m;
    m.utime = e.utime;
    m.blocked = e.blocked;
    m.commanded_angle_rad = commandedAngle(e.utime);
    m.commanded_velocity_rad_s = nominal_.velocityAt(e.utime);
    out.publish(channels::kMotorSwitch, now, m);
    count("switch_edges");
    if (phase_ == Phase::kHomingLeave && !e.blocked) {
      command(now, {StepperCommand::Kind::kStop, 0.0, accel, 0.0});
      phase_until_ = motion_end_ + settle;
      enter(now, Phase::kHomingStop, out);
      homed_ = false;  // stopped past the sheet; seek the edge next
    } else if (phase_ == Phase::kHomingSeek && e.blocked) {
      // The edge defines the home angle: angle(t_edge) = home_angle.
      home_offset_ = rig_.motor.home_angle_deg * kDegToRad - nominal_.angleAt(e.utime);
      homed_ = true;
      count("homings");
      command(now, {StepperCommand::Kind::kStop, 0.0, accel, 0.0});
      phase_until_ = motion_end_ + settle;
      enter(now, Phase::kHomingStop, out);
    }
  }
}

void MotorController::advancePhase(int64_t now, Outbox& out) {
  const double accel = rig_.motor.accel_deg_s2 * kDegToRad;
  const int64_t settle = us(rig_.motor.settle_s);
  switch (phase_) {
    case Phase::kIdle:
      startHoming(now, out);
      break;
    case Phase::kHomingLeave:
    case Phase::kHomingSeek:
      if (std::abs(commandedAngle(now) - seek_start_) > rig_.motor.homing_search_deg * kDegToRad) {
        fault(
            now,
            "home switch not found within " + std::to_string(rig_.motor.homing_search_deg) + " deg",
            out);
      }
      break;
    case Phase::kHomingStop:
      if (now >= phase_until_) {
        if (!homed_) {
          startHoming(now, out);
        } else {
          moveTo(now, startAngle(), rig_.motor.move_speed_deg_s * kDegToRad);
          phase_until_ = motion_end_ + settle + us(rig_.motor.pause_s);
          enter(now, Phase::kPositioning, out);
        }
      }
      break;
    case Phase::kPositioning:
      if (now >= phase_until_) startSweep(now, out);
      break;
    case Phase::kAccelerating:
      if (now >= window_start_) enter(now, Phase::kScanning, out);
      break;
    case Phase::kScanning:
      if (now >= window_end_) closeWindow(now, out);
      break;
    case Phase::kDecelerating:
      if (motion_end_ == INT64_MAX) {
        if (now >= phase_until_) {
          command(now, {StepperCommand::Kind::kStop, 0.0, accel, 0.0});
          phase_until_ = motion_end_ + settle;
        }
      } else if (now >= phase_until_) {
        finishSweep(now, out);
      }
      break;
    case Phase::kReturning:
      if (now >= phase_until_) {
        if (rig_.motor.rehome_every_sweep) {
          startHoming(now, out);
        } else {
          phase_until_ = now + us(rig_.motor.pause_s);
          enter(now, Phase::kPositioning, out);
        }
      }
      break;
    case Phase::kDone:
    case Phase::kFault:
      break;
  }
}

void MotorController::startSweep(int64_t now, Outbox& out) {
  const double accel = rig_.motor.accel_deg_s2 * kDegToRad;
  ++sweep_id_;
  command(now, {StepperCommand::Kind::kRun, omega_, accel, 0.0});
  window_start_ =
      rig_.motor.action_sequence == "naive" ? now : motion_end_ + us(rig_.motor.margin_s);
  window_end_ = window_start_ + window_us_;
  enter(now, now >= window_start_ ? Phase::kScanning : Phase::kAccelerating, out);
}

void MotorController::closeWindow(int64_t now, Outbox& out) {
  scan_window_t w;
  w.utime = now;
  w.sweep_id = sweep_id_;
  w.mode = rig_.motor.mode;
  w.start_utime = window_start_;
  w.end_utime = window_end_;
  w.angular_velocity_rad_s = omega_;
  w.sweep_angle_rad = rig_.motor.sweep_angle_deg * kDegToRad;
  const bool naive = rig_.motor.action_sequence == "naive";
  w.action_sequence = naive ? scan_window_t::NAIVE : scan_window_t::IMPROVED;
  w.accel_overlap = naive;
  out.publish(channels::kScanWindow, now, w);
  phase_until_ = naive ? now : window_end_ + us(rig_.motor.margin_s);
  enter(now, Phase::kDecelerating, out);
  motion_end_ = INT64_MAX;  // stop not yet commanded
}

void MotorController::finishSweep(int64_t now, Outbox& out) {
  ++sweeps_done_;
  count("sweeps");
  if (sweeps_wanted_ > 0 && sweeps_done_ >= sweeps_wanted_) {
    enter(now, Phase::kDone, out);
    return;
  }
  const double target = rig_.motor.rehome_every_sweep
                            ? rig_.motor.home_angle_deg * kDegToRad + kHomingApproachRad
                            : startAngle();
  moveTo(now, target, rig_.motor.move_speed_deg_s * kDegToRad);
  phase_until_ = motion_end_ + us(rig_.motor.settle_s);
  enter(now, Phase::kReturning, out);
}

void MotorController::publishState(int64_t now, Outbox& out) {
  motor_state_t m;
  m.utime = now;
  switch (phase_) {
    case Phase::kIdle:
      m.state = motor_state_t::IDLE;
      break;
    case Phase::kHomingLeave:
    case Phase::kHomingSeek:
    case Phase::kHomingStop:
      m.state = motor_state_t::HOMING;
      break;
    case Phase::kPositioning:
      m.state = motor_state_t::POSITIONING;
      break;
    case Phase::kAccelerating:
      m.state = motor_state_t::ACCELERATING;
      break;
    case Phase::kScanning:
      m.state = motor_state_t::SCANNING;
      break;
    case Phase::kDecelerating:
      m.state = motor_state_t::DECELERATING;
      break;
    case Phase::kReturning:
      m.state = motor_state_t::RETURNING;
      break;
    case Phase::kDone:
      m.state = motor_state_t::DONE;
      break;
    case Phase::kFault:
      m.state = motor_state_t::FAULT;
      break;
  }
  m.homed = homed_;
  m.mode = rig_.motor.mode;
  m.sweep_id = sweep_id_;
  m.sweeps_done = sweeps_done_;
  m.commanded_angle_rad = commandedAngle(now);
  m.commanded_velocity_rad_s = nominal_.velocityAt(now);
  m.detail = detail_.empty() ? phaseName(phase_) : detail_;
  out.publish(channels::kMotorState, now, m);
  const double rate = rig_.motor.status_rate_hz > 0 ? rig_.motor.status_rate_hz : 1.0;
  next_state_utime_ = now + us(1.0 / rate);
}

}  // namespace sweepmap
