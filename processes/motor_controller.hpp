// sweepmap-motor: drives the encoder-less stepper through homing and 3D sweeps with the
// action sequence of Yuan 2021 Fig. 2, and publishes MOTOR_STATE, MOTOR_SWITCH and, when
// a lidar window closes, SCAN_WINDOW.
//
// Improved sequence (default): the motor ramps up before the lidar window opens and
// down after it closes, so the lidar sees only constant angular velocity. The controller
// starts each sweep from -pre_roll (ramp distance + margin) so the window opens near the
// home angle. Naive sequence: window and motor start together (shape error of Fig. 1).
//
// The shaft angle is open loop: the controller's model of what it commanded
// (devices/motion_profile.hpp at nominal acceleration, no delays), referenced to the
// switch edge at homing.
#pragma once

#include "devices/shaft_trajectory.hpp"
#include "devices/stepper_device.hpp"
#include "processes/node.hpp"
#include "rigs/rotating_lidar.hpp"

namespace sweepmap {

class MotorController : public Node {
 public:
  enum class Phase {
    kIdle,
    kHomingLeave,   // blocked at start: move off the shading sheet first
    kHomingSeek,    // move toward the switch edge at homing speed
    kHomingStop,    // edge seen: stopping
    kPositioning,   // move to the sweep's start angle (and pause)
    kAccelerating,  // ramp up; window not yet open
    kScanning,      // lidar window open
    kDecelerating,  // window closed: ramp down
    kReturning,     // move back toward the switch or the start angle
    kDone,
    kFault,
  };

  // `sweeps`: number of 3D sweeps to make, 0 = until stopped. `start_utime`: time origin.
  MotorController(const RotatingLidarConfig& rig, StepperDevice* device, int sweeps,
                  int64_t start_utime);
  std::vector<std::string> subscriptions() const override { return {}; }

  Phase phase() const { return phase_; }
  bool done() const { return phase_ == Phase::kDone || phase_ == Phase::kFault; }
  int sweepsDone() const { return sweeps_done_; }
  // Commanded (open-loop) shaft angle [rad]; 0 = X_L along the rig's front, the switch
  // edge is at motor.home_angle_deg.
  double commandedAngle(int64_t utime) const;
  // Nominal timing of one sweep in the configured mode.
  double omega() const { return omega_; }
  double preRollAngle() const;
  int64_t windowDurationUs() const { return window_us_; }

 protected:
  void handle(const Message& msg, Outbox& out) override {}
  void advance(int64_t now_utime, Outbox& out) override;

 private:
  void command(int64_t now, const StepperCommand& cmd);
  void moveTo(int64_t now, double angle_rad, double speed_rad_s);
  void enter(int64_t now, Phase phase, Outbox& out);
  void publishState(int64_t now, Outbox& out);
  void startHoming(int64_t now, Outbox& out);
  void fault(int64_t now, const std::string& why, Outbox& out);
  // The steps of advance(): the switch's edges (publish; homing reacts to them), then the
  // phase's own transition.
  void handleSwitchEdges(int64_t now, Outbox& out);
  void advancePhase(int64_t now, Outbox& out);
  void startSweep(int64_t now, Outbox& out);   // positioned: run up, open the window
  void closeWindow(int64_t now, Outbox& out);  // window over: publish SCAN_WINDOW
  void finishSweep(int64_t now, Outbox& out);  // stopped: done, or back to the start
  double startAngle() const;                   // of each sweep (-pre-roll; naive: 0)

  RotatingLidarConfig rig_;
  StepperDevice* device_;
  int sweeps_wanted_;
  Phase phase_ = Phase::kIdle;
  ShaftTrajectory nominal_;   // controller's open-loop model, device step frame
  double home_offset_ = 0.0;  // angle = nominal + offset (set by homing)
  bool homed_ = false;
  int64_t motion_end_ = 0;   // nominal end of the last command
  int64_t phase_until_ = 0;  // when the current phase's wait ends
  double seek_start_ = 0.0;
  int64_t window_start_ = 0;
  int64_t window_end_ = 0;
  int64_t sweep_id_ = -1;
  int sweeps_done_ = 0;
  double omega_ = 0.0;
  int64_t window_us_ = 0;
  int64_t next_state_utime_ = 0;
  std::string detail_;
};

const char* phaseName(MotorController::Phase phase);

}  // namespace sweepmap
