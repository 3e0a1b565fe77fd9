#include <gtest/gtest.h>

#include <cmath>

#include "core/angles.hpp"
#include "processes/channels.hpp"
#include "processes/motor_controller.hpp"
#include "processes/offline_bus.hpp"
#include "processes/sim_setup.hpp"
#include "sim/stepper.hpp"
#include "sweepmap/motor_state_t.hpp"
#include "sweepmap/scan_window_t.hpp"

namespace sweepmap {
namespace {

struct ControllerRun {
  std::vector<scan_window_t> windows;
  std::vector<int8_t> states;
  bool fault = false;
  int sweeps = 0;
};

SimRigConfig exactDevice() {
  SimRigConfig s;
  s.accel_jitter = 0.0;
  s.start_delay_max_ms = 0.0;
  s.switch_response_ms = 0.0;
  s.switch_response_jitter_ms = 0.0;
  s.switch_hysteresis_deg = 0.0;
  return s;
}

// Runs the controller against a simulated stepper on a 1 ms virtual clock.
ControllerRun runController(const RotatingLidarConfig& rig, int sweeps, uint64_t seed,
                            SimStepper** keep = nullptr,
                            std::unique_ptr<SimStepper>* owner = nullptr) {
  const int64_t t0 = kSimEpochUtime;
  auto stepper = std::make_unique<SimStepper>(rig.motor, rig.sim, seed, 0.8, t0, nullptr);
  MotorController motor(rig, stepper.get(), sweeps, t0);
  OfflineBus bus;
  bus.attach(&motor);
  ControllerRun run;
  bus.setSink([&](const Message& m) {
    if (m.channel == channels::kScanWindow) {
      scan_window_t w;
      EXPECT_TRUE(decodeMessage(m, &w));
      run.windows.push_back(w);
    } else if (m.channel == channels::kMotorState) {
      motor_state_t s;
      EXPECT_TRUE(decodeMessage(m, &s));
      if (run.states.empty() || run.states.back() != s.state) run.states.push_back(s.state);
    }
  });
  const int64_t limit = t0 + static_cast<int64_t>(sweeps * 60e6);
  for (int64_t t = t0; t < limit && !motor.done(); t += 1000) bus.tick(t);
  run.fault = motor.phase() == MotorController::Phase::kFault;
  run.sweeps = motor.sweepsDone();
  if (owner) *owner = std::move(stepper);
  return run;
}

class ActionSequenceTiming : public ::testing::TestWithParam<int> {};

// Improved sequence, every mode: the window lasts T of Table 1, the commanded speed is
// 180 deg / T, and the TRUE shaft turns at exactly that constant speed through the whole
// window, even with the section-2 errors of the default error model.
TEST_P(ActionSequenceTiming, ImprovedWindowSeesOnlyConstantSpeed) {
  const int mode = GetParam();
  for (const bool errors : {false, true}) {
    RotatingLidarConfig rig;
    rig.motor.mode = mode;
    if (!errors) rig.sim = exactDevice();
    std::unique_ptr<SimStepper> stepper;
    const ControllerRun run = runController(rig, 2, 42 + mode, nullptr, &stepper);
    ASSERT_FALSE(run.fault);
    ASSERT_EQ(run.windows.size(), 2u);
    const ScanMode m = scanMode(mode);
    for (const auto& w : run.windows) {
      EXPECT_EQ(w.end_utime - w.start_utime, static_cast<int64_t>(m.period_s * 1e6));
      EXPECT_NEAR(w.angular_velocity_rad_s, M_PI / m.period_s, 1e-12);
      EXPECT_FALSE(w.accel_overlap);
      EXPECT_EQ(w.mode, mode);
      const auto& truth = stepper->trajectory();
      for (int64_t t = w.start_utime; t <= w.end_utime; t += 5000) {
        ASSERT_NEAR(truth.velocityAt(t), w.angular_velocity_rad_s, 1e-9)
            << "mode " << mode << " errors " << errors << " at +" << (t - w.start_utime) << " us";
      }
      // The window opens near the home angle (shaft angle 0); with an exact device exactly.
      const double start_angle = truth.angleAt(w.start_utime);
      if (!errors) {
        EXPECT_NEAR(start_angle, 0.0, 1e-6) << "mode " << mode;
      } else {
        // Every command starts up to 30 ms late: the stop at the homing edge overshoots by
        // up to 30 ms at homing speed, the sweep's run starts up to 30 ms late at omega.
        // Ramps vary by +-10 % of their distance; the switch answers 2 +- 1 ms late and
        // its edge sits half the hysteresis off.
        const double omega = M_PI / m.period_s;
        const double v_home = rig.motor.homing_speed_deg_s * kDegToRad;
        const double a = rig.motor.accel_deg_s2 * kDegToRad;
        const double bound = 0.030 * (omega + v_home) +
                             0.11 * (omega * omega + v_home * v_home) / (2 * a) + 0.003 * v_home +
                             0.5 * rig.sim.switch_hysteresis_deg * kDegToRad + 0.1 * kDegToRad;
        EXPECT_LT(std::abs(start_angle), bound) << "mode " << mode;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllModes, ActionSequenceTiming, ::testing::Range(1, 8));

TEST(MotorController, NaiveSequenceOverlapsRamp) {
  RotatingLidarConfig rig;
  rig.motor.mode = 1;
  rig.motor.action_sequence = "naive";
  rig.sim = exactDevice();
  std::unique_ptr<SimStepper> stepper;
  const ControllerRun run = runController(rig, 1, 3, nullptr, &stepper);
  ASSERT_EQ(run.windows.size(), 1u);
  const auto& w = run.windows[0];
  EXPECT_TRUE(w.accel_overlap);
  EXPECT_EQ(w.action_sequence, int8_t{scan_window_t::NAIVE});
  // The shaft is still accelerating when the window opens.
  EXPECT_LT(stepper->trajectory().velocityAt(w.start_utime + 10000),
            0.5 * w.angular_velocity_rad_s);
}

TEST(MotorController, GoesThroughHomingScanningAndDone) {
  RotatingLidarConfig rig;
  rig.motor.mode = 1;
  const ControllerRun run = runController(rig, 1, 9);
  ASSERT_GE(run.states.size(), 5u);
  EXPECT_EQ(run.states.front(), int8_t{motor_state_t::HOMING});
  EXPECT_EQ(run.states.back(), int8_t{motor_state_t::DONE});
  EXPECT_NE(std::find(run.states.begin(), run.states.end(), int8_t{motor_state_t::SCANNING}),
            run.states.end());
  EXPECT_EQ(run.sweeps, 1);
}

// A switch that never triggers: homing gives up with a fault instead of turning forever.
class DeadSwitchStepper : public StepperDevice {
 public:
  void command(int64_t, const StepperCommand&) override { ++commands; }
  std::vector<SwitchEdge> poll(int64_t) override { return {}; }
  bool switchBlocked() const override { return false; }
  int commands = 0;
};

TEST(MotorController, FaultsWhenHomeSwitchNeverSeen) {
  RotatingLidarConfig rig;
  DeadSwitchStepper dead;
  MotorController motor(rig, &dead, 1, 0);
  OfflineBus bus;
  bus.attach(&motor);
  for (int64_t t = 0; t < 60000000 && !motor.done(); t += 1000) bus.tick(t);
  EXPECT_EQ(motor.phase(), MotorController::Phase::kFault);
  EXPECT_TRUE(motor.failed());
  EXPECT_GE(dead.commands, 2);  // seek, then stop
}

}  // namespace
}  // namespace sweepmap
