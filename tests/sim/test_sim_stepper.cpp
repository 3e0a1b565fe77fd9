#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "core/angles.hpp"
#include "sim/stepper.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kStartUtime = 1'000'000;

SimRigConfig perfectSim() {
  SimRigConfig sim;
  sim.accel_jitter = 0.0;
  sim.start_delay_max_ms = 0.0;
  sim.switch_response_ms = 2.0;
  sim.switch_response_jitter_ms = 0.0;
  sim.switch_hysteresis_deg = 0.3;
  return sim;
}

StepperCommand run(double velocity_rad_s, double accel_rad_s2) {
  StepperCommand c;
  c.kind = StepperCommand::Kind::kRun;
  c.velocity_rad_s = velocity_rad_s;
  c.accel_rad_s2 = accel_rad_s2;
  return c;
}

StepperCommand moveBy(double delta_rad, double speed_rad_s, double accel_rad_s2) {
  StepperCommand c;
  c.kind = StepperCommand::Kind::kMoveBy;
  c.velocity_rad_s = speed_rad_s;
  c.accel_rad_s2 = accel_rad_s2;
  c.delta_rad = delta_rad;
  return c;
}

// A stepper whose emitted truth segments are recorded.
class SimStepperTest : public ::testing::Test {
 protected:
  void make(const SimRigConfig& sim, uint64_t seed, double initial_angle_rad) {
    segments_.clear();
    stepper_ =
        std::make_unique<SimStepper>(motor_, sim, seed, initial_angle_rad, kStartUtime,
                                     [this](const ShaftSegment& s) { segments_.push_back(s); });
  }
  // Polls every `step_us` up to `until_utime`; checks each edge is reported at the first
  // poll at or after its report time.
  std::vector<SwitchEdge> pollUntil(int64_t until_utime, int64_t step_us = 100) {
    std::vector<SwitchEdge> edges;
    for (; now_ <= until_utime; now_ += step_us) {
      for (const SwitchEdge& e : stepper_->poll(now_)) {
        EXPECT_LE(e.utime, now_);
        EXPECT_GT(e.utime, now_ - step_us);
        edges.push_back(e);
      }
    }
    return edges;
  }
  // Segments of the last command are continuous in angle and velocity.
  void expectContinuous(size_t first) const {
    for (size_t i = first + 1; i < segments_.size(); ++i) {
      const ShaftSegment& a = segments_[i - 1];
      const ShaftSegment& b = segments_[i];
      const double dt = double(b.start_utime - a.start_utime) * 1e-6;
      EXPECT_GT(b.start_utime, a.start_utime);
      EXPECT_NEAR(a.angle_rad + a.velocity_rad_s * dt + 0.5 * a.accel_rad_s2 * dt * dt, b.angle_rad,
                  1e-12);
      EXPECT_NEAR(a.velocity_rad_s + a.accel_rad_s2 * dt, b.velocity_rad_s, 1e-12);
    }
  }

  MotorConfig motor_;  // home_angle_deg = 0
  std::vector<ShaftSegment> segments_;
  std::unique_ptr<SimStepper> stepper_;
  int64_t now_ = kStartUtime;
};

TEST_F(SimStepperTest, ConstructionEmitsStandstill) {
  make(perfectSim(), 1, 0.7);
  ASSERT_EQ(segments_.size(), 1u);
  EXPECT_EQ(segments_[0].start_utime, kStartUtime);
  EXPECT_EQ(segments_[0].angle_rad, 0.7);
  EXPECT_EQ(segments_[0].velocity_rad_s, 0.0);
  EXPECT_EQ(segments_[0].accel_rad_s2, 0.0);
  EXPECT_TRUE(stepper_->trajectory().covers(kStartUtime));
  EXPECT_FALSE(stepper_->trajectory().covers(kStartUtime - 1));
}

TEST_F(SimStepperTest, MoveByTurnsExactlyDeltaWithJitter) {
  const SimRigConfig sim;  // default error model: delays and acceleration jitter on
  for (uint64_t seed = 0; seed < 50; ++seed) {
    for (double delta : {1.3, -0.4, 0.01}) {  // trapezoids both ways, and a triangle
      make(sim, seed, 0.7);
      stepper_->command(2'000'000, moveBy(delta, 1.5, 12.0));
      ASSERT_GE(segments_.size(), 3u);
      expectContinuous(1);
      const ShaftSegment& last = segments_.back();
      EXPECT_NEAR(last.angle_rad, 0.7 + delta, 1e-12) << "seed " << seed;
      EXPECT_EQ(last.velocity_rad_s, 0.0);
      EXPECT_EQ(last.accel_rad_s2, 0.0);
      const ShaftTrajectory& truth = stepper_->trajectory();
      EXPECT_NEAR(truth.angleAt(last.start_utime + 10'000'000), 0.7 + delta, 1e-12);
      for (const ShaftSegment& s : segments_) EXPECT_LE(std::abs(s.velocity_rad_s), 1.5 + 1e-3);
    }
  }
}

TEST_F(SimStepperTest, MoveByWhileTurningStopsFirst) {
  make(perfectSim(), 3, 0.0);
  stepper_->command(2'000'000, run(1.0, 4.0));
  const size_t first = segments_.size();
  stepper_->command(3'000'000, moveBy(0.5, 1.0, 4.0));
  ASSERT_GE(segments_.size(), first + 3);
  expectContinuous(first);
  EXPECT_EQ(segments_[first].velocity_rad_s, 1.0);      // still running when it takes effect
  EXPECT_EQ(segments_[first + 1].velocity_rad_s, 0.0);  // stopped, then the move
  EXPECT_NEAR(segments_.back().angle_rad, segments_[first + 1].angle_rad + 0.5, 1e-12);
  EXPECT_EQ(segments_.back().velocity_rad_s, 0.0);
}

TEST_F(SimStepperTest, RunReachesAndHoldsItsVelocity) {
  make(SimRigConfig(), 5, 0.0);
  stepper_->command(2'000'000, run(-1.2, 5.0));
  expectContinuous(1);
  const ShaftTrajectory& truth = stepper_->trajectory();
  const int64_t t_eff = segments_[1].start_utime;
  EXPECT_EQ(truth.velocityAt(t_eff + 2'000'000), -1.2);  // ramp <= 1.2 / (5 * 0.9) s
  EXPECT_EQ(segments_.back().velocity_rad_s, -1.2);
  EXPECT_EQ(segments_.back().accel_rad_s2, 0.0);
  stepper_->command(4'000'000, StepperCommand{StepperCommand::Kind::kStop, 0.0, 5.0, 0.0});
  EXPECT_EQ(truth.velocityAt(7'000'000), 0.0);
}

TEST_F(SimStepperTest, StartDelayAndAccelJitterStayWithinBounds) {
  SimRigConfig sim;
  sim.start_delay_max_ms = 30.0;
  sim.accel_jitter = 0.1;
  const double accel = 4 * M_PI, speed = M_PI / 2;  // ramp of exactly 125 ms
  double min_delay = 1e9, max_delay = -1e9, min_factor = 1e9, max_factor = -1e9;
  for (uint64_t seed = 0; seed < 200; ++seed) {
    make(sim, seed, 0.0);
    stepper_->command(2'000'000, run(speed, accel));
    ASSERT_EQ(segments_.size(), 3u);
    const double delay_ms = double(segments_[1].start_utime - 2'000'000) / 1000.0;
    const double factor = segments_[1].accel_rad_s2 / accel;
    EXPECT_GE(delay_ms, 0.0);
    EXPECT_LE(delay_ms, 30.0);
    EXPECT_GE(factor, 0.9 - 1e-4);  // 1e-4: the ramp's rounding to whole microseconds
    EXPECT_LE(factor, 1.1 + 1e-4);
    min_delay = std::min(min_delay, delay_ms);
    max_delay = std::max(max_delay, delay_ms);
    min_factor = std::min(min_factor, factor);
    max_factor = std::max(max_factor, factor);
  }
  // Spread over the whole range, not stuck at one value.
  EXPECT_LT(min_delay, 3.0);
  EXPECT_GT(max_delay, 27.0);
  EXPECT_LT(min_factor, 0.92);
  EXPECT_GT(max_factor, 1.08);

  for (uint64_t seed = 0; seed < 20; ++seed) {
    make(perfectSim(), seed, 0.0);
    stepper_->command(2'000'000, run(speed, accel));
    ASSERT_EQ(segments_.size(), 3u);
    EXPECT_EQ(segments_[1].start_utime, 2'000'000);
    EXPECT_EQ(segments_[2].start_utime, 2'125'000);
    EXPECT_NEAR(segments_[1].accel_rad_s2, accel, 1e-12);
  }
}

TEST_F(SimStepperTest, CommandsExecuteInOrder) {
  SimRigConfig sim;
  sim.start_delay_max_ms = 30.0;
  for (uint64_t seed = 0; seed < 50; ++seed) {
    make(sim, seed, 0.0);
    stepper_->command(2'000'000, run(1.0, 4.0));
    const int64_t first_effect = segments_[1].start_utime;
    const size_t n = segments_.size();
    stepper_->command(2'000'100, run(-1.0, 4.0));
    EXPECT_GE(segments_[n].start_utime, first_effect);
  }
}

TEST_F(SimStepperTest, SameSeedSameMotion) {
  const auto motion = [this](uint64_t seed) {
    make(SimRigConfig(), seed, 0.2);
    stepper_->command(2'000'000, run(1.0, 4.0));
    stepper_->command(3'000'000, moveBy(-0.3, 1.0, 4.0));
    return segments_;
  };
  const auto a = motion(11), b = motion(11), c = motion(12);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].start_utime, b[i].start_utime);
    EXPECT_EQ(a[i].angle_rad, b[i].angle_rad);
    EXPECT_EQ(a[i].accel_rad_s2, b[i].accel_rad_s2);
  }
  EXPECT_NE(a[1].start_utime + a[1].accel_rad_s2, c[1].start_utime + c[1].accel_rad_s2);
}

TEST_F(SimStepperTest, InitialSwitchLevelFromTheSheet) {
  for (double deg : {-10.0, -89.0, 0.0, 350.0}) {  // in (home - 90, home] modulo 360
    make(perfectSim(), 1, deg * kDegToRad);
    EXPECT_TRUE(stepper_->switchBlocked()) << deg;
  }
  for (double deg : {0.5, -91.0, 180.0, -270.0}) {
    make(perfectSim(), 1, deg * kDegToRad);
    EXPECT_FALSE(stepper_->switchBlocked()) << deg;
  }
}

// Crossing time of `level` on a constant-velocity segment.
double crossingOnCruise(const ShaftSegment& s, double level_rad) {
  EXPECT_EQ(s.accel_rad_s2, 0.0);
  return double(s.start_utime) + (level_rad - s.angle_rad) / s.velocity_rad_s * 1e6;
}

TEST_F(SimStepperTest, EdgesAtCrossingPlusResponseInBothDirectionsWithHysteresis) {
  make(perfectSim(), 1, -10.0 * kDegToRad);
  const double speed = 20.0 * kDegToRad, accel = 720.0 * kDegToRad, h = 0.3 * kDegToRad;
  ASSERT_TRUE(stepper_->switchBlocked());

  // Turning positive: the sheet leaves the beam at home + h/2.
  stepper_->command(now_, run(speed, accel));
  const double leave = crossingOnCruise(segments_.back(), h / 2);
  auto edges = pollUntil(kStartUtime + 1'500'000);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_FALSE(edges[0].blocked);
  EXPECT_EQ(edges[0].utime, std::llround(leave + 2000.0));
  EXPECT_FALSE(stepper_->switchBlocked());

  // Turning negative: it enters at home - h/2 ...
  stepper_->command(now_, run(-speed, accel));
  const double enter = crossingOnCruise(segments_.back(), -h / 2);
  // ... and leaves the far end at home - 90 deg - h/2.
  const double leave_far = crossingOnCruise(segments_.back(), -90.0 * kDegToRad - h / 2);
  edges = pollUntil(kStartUtime + 8'000'000);
  ASSERT_EQ(edges.size(), 2u);
  EXPECT_TRUE(edges[0].blocked);
  EXPECT_EQ(edges[0].utime, std::llround(enter + 2000.0));
  EXPECT_FALSE(edges[1].blocked);
  EXPECT_EQ(edges[1].utime, std::llround(leave_far + 2000.0));

  // Back positive: enters the far end at home - 90 deg + h/2.
  stepper_->command(now_, run(speed, accel));
  const double enter_far = crossingOnCruise(segments_.back(), -90.0 * kDegToRad + h / 2);
  edges = pollUntil(now_ + 1'500'000);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_TRUE(edges[0].blocked);
  EXPECT_EQ(edges[0].utime, std::llround(enter_far + 2000.0));
  EXPECT_TRUE(stepper_->switchBlocked());
}

TEST_F(SimStepperTest, EdgeDuringARampIsExactToAMicrosecond) {
  SimRigConfig sim = perfectSim();
  sim.switch_response_jitter_ms = 1.0;
  const double h = 0.3 * kDegToRad;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    now_ = kStartUtime;
    make(sim, seed, -0.5 * kDegToRad);
    // Ramp of 1 deg at 200 deg/s^2: the edge at +0.15 deg is crossed while accelerating.
    stepper_->command(now_, run(20.0 * kDegToRad, 200.0 * kDegToRad));
    const auto edges = pollUntil(kStartUtime + 300'000);
    ASSERT_EQ(edges.size(), 1u);
    const ShaftTrajectory& truth = stepper_->trajectory();
    ASSERT_NE(truth.velocityAt(edges[0].utime - 1000), 20.0 * kDegToRad);  // still in the ramp
    // Reported 1..3 ms after the crossing.
    EXPECT_LT(truth.angleAt(edges[0].utime - 3001), h / 2);
    EXPECT_GT(truth.angleAt(edges[0].utime - 999), h / 2);
  }
  // Without jitter the crossing is pinned to the microsecond.
  now_ = kStartUtime;
  make(perfectSim(), 1, -0.5 * kDegToRad);
  stepper_->command(now_, run(20.0 * kDegToRad, 200.0 * kDegToRad));
  const auto edges = pollUntil(kStartUtime + 300'000);
  ASSERT_EQ(edges.size(), 1u);
  const ShaftTrajectory& truth = stepper_->trajectory();
  EXPECT_LT(truth.angleAt(edges[0].utime - 2001), h / 2);
  EXPECT_GT(truth.angleAt(edges[0].utime - 1999), h / 2);
}

TEST_F(SimStepperTest, ReversalInsideTheHysteresisBandKeepsTheLevel) {
  make(perfectSim(), 1, 0.05 * kDegToRad);  // just clear of the sheet
  ASSERT_FALSE(stepper_->switchBlocked());
  const double speed = 10.0 * kDegToRad, accel = 100.0 * kDegToRad;
  stepper_->command(now_, moveBy(-0.1 * kDegToRad, speed, accel));  // to -0.05: inside the band
  EXPECT_TRUE(pollUntil(now_ + 500'000).empty());
  EXPECT_FALSE(stepper_->switchBlocked());
  stepper_->command(now_, moveBy(-0.2 * kDegToRad, speed, accel));  // to -0.25: past home - h/2
  auto edges = pollUntil(now_ + 500'000);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_TRUE(edges[0].blocked);
  stepper_->command(now_, moveBy(0.3 * kDegToRad, speed, accel));  // to +0.05: short of home + h/2
  EXPECT_TRUE(pollUntil(now_ + 500'000).empty());
  EXPECT_TRUE(stepper_->switchBlocked());
  stepper_->command(now_, moveBy(0.2 * kDegToRad, speed, accel));  // to +0.25
  edges = pollUntil(now_ + 500'000);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_FALSE(edges[0].blocked);
}

TEST_F(SimStepperTest, HomingSearchOverSeveralTurnsAlternatesEdges) {
  SimRigConfig sim;  // default error model
  make(sim, 9, 100.0 * kDegToRad);
  stepper_->command(now_, run(360.0 * kDegToRad, 720.0 * kDegToRad));  // 1 turn/s
  const auto edges = pollUntil(kStartUtime + 3'600'000, 1000);
  // Three full turns: the far end and home once each per turn.
  ASSERT_GE(edges.size(), 6u);
  for (size_t i = 0; i < edges.size(); ++i) {
    EXPECT_EQ(edges[i].blocked, i % 2 == 0) << i;
    if (i > 0) {
      EXPECT_GT(edges[i].utime, edges[i - 1].utime);
    }
  }
}

TEST_F(SimStepperTest, RejectsInvalidCommands) {
  make(perfectSim(), 1, 0.0);
  EXPECT_THROW(stepper_->command(now_, run(1.0, 0.0)), std::invalid_argument);
  EXPECT_THROW(stepper_->command(now_, run(NAN, 1.0)), std::invalid_argument);
  EXPECT_THROW(stepper_->command(now_, moveBy(1.0, 0.0, 1.0)), std::invalid_argument);
  EXPECT_EQ(segments_.size(), 1u);
}

}  // namespace
}  // namespace sweepmap
