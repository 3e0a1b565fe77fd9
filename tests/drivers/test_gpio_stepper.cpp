// Rig A's stepper and home switch on GPIO, against the fake chip on a virtual clock: the
// MotorController's real commands turned into STEP/DIR pulses, the switch it homes on
// driven by a simulated shaft that integrates those pulses.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <functional>
#include <iostream>
#include <memory>
#include <thread>

#include "core/angles.hpp"
#include "core/config.hpp"
#include "drivers/gpio/fake_gpio_backend.hpp"
#include "drivers/gpio/gpio_stepper.hpp"
#include "drivers/gpio/gpiod_backend.hpp"
#include "drivers/gpio/switch_debouncer.hpp"
#include "processes/motor_controller.hpp"
#include "rigs/rotating_lidar.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kT0Utime = 1'700'000'000'000'000;  // the plan's clock = the virtual clock
constexpr int kStep = 17, kDir = 27, kEnable = 22, kHome = 23;
constexpr double kInitialUnblockedRad = 0.8;  // 46 deg above the edge: the beam is clear
constexpr double kInitialBlockedRad = -0.5;   // on the sheet

GpioStepperOptions fakeOptions() {
  GpioStepperOptions o;
  o.lines.chip = "fake-gpiochip";
  o.lines.step = kStep;
  o.lines.dir = kDir;
  o.lines.enable = kEnable;
  o.lines.home = kHome;
  o.dedicated_thread = false;  // steps are made by poll() on the virtual clock
  return o;
}

StepperCommand moveBy(double delta_rad, double speed_rad_s, double accel_rad_s2) {
  return {StepperCommand::Kind::kMoveBy, speed_rad_s, accel_rad_s2, delta_rad};
}

// A STEP pulse as the driver board sees it.
struct SeenStep {
  int64_t t_ns = 0;        // rising edge
  int direction = 0;       // from DIR at that moment
  int64_t dir_set_ns = 0;  // when DIR last changed before it
};

std::vector<SeenStep> seenSteps(const FakeGpioBackend& gpio, bool dir_positive_high = true) {
  std::vector<SeenStep> steps;
  bool dir_high = dir_positive_high;
  int64_t dir_set_ns = INT64_MIN / 2;
  bool step_high = false;
  for (const auto& c : gpio.outputs()) {
    if (c.offset == kDir && c.high != dir_high) {
      dir_high = c.high;
      dir_set_ns = c.t_ns;
    } else if (c.offset == kStep) {
      if (c.high && !step_high) {
        steps.push_back({c.t_ns, dir_high == dir_positive_high ? 1 : -1, dir_set_ns});
      }
      step_high = c.high;
    }
  }
  return steps;
}

// The shaft and the home switch behind the fake chip: each STEP pulse turns the shaft by one
// step in DIR's direction; the shading sheet covers (home - 90 deg, home] (as in the
// SimStepper), and every change of the beam is injected as an edge at the step's time,
// followed by `bounces` extra toggles 100 us apart (ending at the new level).
class FakeShaft {
 public:
  FakeShaft(FakeGpioBackend& gpio, const GpioStepperOptions& o, double initial_rad, double home_rad,
            int bounces = 0)
      : gpio_(gpio), o_(o), initial_rad_(initial_rad), home_rad_(home_rad), bounces_(bounces) {
    blocked_ = blockedAt(initial_rad);
    gpio.setInputLevel(o.lines.home, blocked_ == o.lines.home_blocked_high);
    gpio.setOnOutput([this](const FakeGpioBackend::OutputChange& c) { onOutput(c); });
  }
  double angle() const { return initial_rad_ + double(position_) * o_.stepRad(); }
  int transitions() const { return transitions_; }
  bool blocked() const { return blocked_; }

 private:
  bool blockedAt(double angle_rad) const {
    const double rel = wrapAngle(angle_rad - home_rad_);
    return rel > -M_PI / 2 && rel <= 0.0;
  }
  void onOutput(const FakeGpioBackend::OutputChange& c) {
    if (c.offset == o_.lines.dir) dir_high_ = c.high;
    if (c.offset != o_.lines.step || !c.high) return;
    position_ += dir_high_ == o_.lines.dir_positive_high ? 1 : -1;
    if (blockedAt(angle()) == blocked_) return;
    blocked_ = !blocked_;
    ++transitions_;
    const bool level = blocked_ == o_.lines.home_blocked_high;
    gpio_.injectEdge(o_.lines.home, c.t_ns, level);
    for (int i = 1; i <= 2 * bounces_; ++i) {
      gpio_.injectEdge(o_.lines.home, c.t_ns + i * 100'000, i % 2 == 0 ? level : !level);
    }
  }

  FakeGpioBackend& gpio_;
  GpioStepperOptions o_;
  double initial_rad_;
  double home_rad_;
  int bounces_;
  bool dir_high_ = true;
  int64_t position_ = 0;
  bool blocked_ = false;
  int transitions_ = 0;
};

// The analytic time [ns] at which the planned motion crosses `level_rad` going in
// `direction`, at or after `from_ns`: the textbook quadratic per segment, in long double.
long double analyticCrossingNs(const ShaftTrajectory& plan, long double level_rad, int direction,
                               int64_t from_ns) {
  const auto& segs = plan.segments();
  for (size_t i = 0; i < segs.size(); ++i) {
    const auto& s = segs[i];
    const long double start_ns = (long double)s.start_utime * 1000;
    const long double end_ns =
        i + 1 < segs.size() ? (long double)segs[i + 1].start_utime * 1000 : 1e30L;
    if (end_ns < from_ns - 1000) continue;
    const long double c = (long double)s.angle_rad - level_rad;
    const long double v = s.velocity_rad_s, a = s.accel_rad_s2;
    std::vector<long double> taus;
    if (a == 0) {
      if (v != 0) taus.push_back(-c / v);
    } else {
      long double disc = v * v - 2 * a * c;
      if (disc < 0 && disc > -1e-9L) disc = 0;  // touching: a move ending on a step angle
      if (disc >= 0) {
        taus.push_back((-v - std::sqrt(disc)) / a);
        taus.push_back((-v + std::sqrt(disc)) / a);
      }
    }
    std::sort(taus.begin(), taus.end());
    for (const long double tau : taus) {
      const long double t_ns = start_ns + tau * 1e9L;
      if (t_ns < std::max<long double>(start_ns, from_ns) - 2000 || t_ns > end_ns + 1) continue;
      const long double slope = v + a * tau;
      if (slope * direction >= -1e-6L) return t_ns;
    }
  }
  return NAN;
}

struct TimingCheck {
  long double max_error_ns = 0;
  int64_t net_steps = 0;
  int64_t min_setup_ns = INT64_MAX;
};

// Every emitted step against the analytic crossing of its step angle in the plan.
TimingCheck checkStepTimes(const std::vector<SeenStep>& steps, const ShaftTrajectory& plan,
                           double step_rad) {
  TimingCheck check;
  int64_t position = 0;
  int64_t from_ns = plan.segments().front().start_utime * 1000;
  for (const SeenStep& s : steps) {
    position += s.direction;
    const long double t =
        analyticCrossingNs(plan, (long double)position * step_rad, s.direction, from_ns);
    EXPECT_FALSE(std::isnan(t)) << "no crossing for step " << position;
    check.max_error_ns = std::max(check.max_error_ns, std::abs((long double)s.t_ns - t));
    check.min_setup_ns = std::min(check.min_setup_ns, s.t_ns - s.dir_set_ns);
    from_ns = s.t_ns;
  }
  check.net_steps = position;
  return check;
}

// The MotorController driving a GpioStepper on the fake chip over a 1 ms virtual clock.
struct ControllerRig {
  explicit ControllerRig(RotatingLidarConfig rig_config, double initial_rad, int bounces = 0,
                         GpioStepperOptions options = fakeOptions())
      : rig(std::move(rig_config)),
        clock(kT0Utime * 1000),
        gpio(clock),
        shaft(gpio, options, initial_rad, rig.motor.home_angle_deg * kDegToRad, bounces),
        stepper(std::make_unique<GpioStepper>(options, gpio, clock, kT0Utime)),
        controller(rig, stepper.get(), 1, kT0Utime) {}

  // Ticks until `done` or the controller finishes; returns the time reached.
  int64_t runUntil(const std::function<bool()>& done, double limit_s) {
    const int64_t limit = now + static_cast<int64_t>(limit_s * 1e6);
    for (; now < limit && !controller.done() && !done(); now += 1000) {
      Outbox out;
      controller.tick(now, out);
    }
    return now;
  }

  RotatingLidarConfig rig;
  VirtualClock clock;
  FakeGpioBackend gpio;
  FakeShaft shaft;
  std::unique_ptr<GpioStepper> stepper;
  MotorController controller;
  int64_t now = kT0Utime;
};

class SweepStepTiming : public ::testing::TestWithParam<int> {};

// A whole mode-1 / mode-7 sweep (homing, positioning, the run through the window, the stop
// and the return) as the controller commands it: each STEP at the analytic crossing time of
// its step angle in the commanded trapezoids, DIR stable before every STEP.
TEST_P(SweepStepTiming, StepsAtTheCommandedCrossings) {
  RotatingLidarConfig rig;
  rig.motor.mode = GetParam();
  ControllerRig r(rig, kInitialUnblockedRad);
  r.runUntil([] { return false; }, 120);
  ASSERT_EQ(r.controller.phase(), MotorController::Phase::kDone);
  const auto steps = seenSteps(r.gpio);
  const TimingCheck check = checkStepTimes(steps, r.stepper->plan(), fakeOptions().stepRad());
  std::cout << "mode " << GetParam() << ": " << steps.size() << " steps, largest |emitted - "
            << "analytic| = " << double(check.max_error_ns) << " ns, shortest DIR setup "
            << check.min_setup_ns << " ns\n";
  RecordProperty("max_step_time_error_ns", std::to_string(double(check.max_error_ns)));
  // The virtual clock has 1 ns resolution (0.5 ns rounding); a move that ends exactly on a
  // step angle makes that step sqrt(2 * 1e-12 rad / accel) early (0.4 us at 720 deg/s^2).
  EXPECT_LT(check.max_error_ns, 1000.0L);
  EXPECT_GE(check.min_setup_ns, fakeOptions().timing.dir_setup_ns);
  EXPECT_EQ(check.net_steps, r.stepper->position());
  EXPECT_GT(steps.size(), 1600u);  // at least the 180 deg window
}

INSTANTIATE_TEST_SUITE_P(Modes1And7, SweepStepTiming, ::testing::Values(1, 7));

// A move by exactly N step angles makes exactly N steps, either way; a run and a stop make as
// many as the planned angle has crossed.
TEST(GpioStepper, StepCountIsTheCommandedAngleOverTheStepAngle) {
  const GpioStepperOptions o = fakeOptions();
  VirtualClock clock(kT0Utime * 1000);
  FakeGpioBackend gpio(clock);
  GpioStepper stepper(o, gpio, clock, kT0Utime);
  const double d = o.stepRad();
  const double a = 720 * kDegToRad;
  int64_t t = kT0Utime;
  stepper.command(t, moveBy(1600 * d, M_PI / 2, a));  // 180 deg
  stepper.poll(t += 5'000'000);
  EXPECT_EQ(stepper.position(), 1600);
  stepper.command(t, moveBy(-2437 * d, M_PI / 2, a));
  stepper.poll(t += 5'000'000);
  EXPECT_EQ(stepper.position(), 1600 - 2437);
  stepper.command(t, {StepperCommand::Kind::kRun, 0.7, a, 0.0});
  stepper.poll(t += 1'000'000);
  stepper.command(t, {StepperCommand::Kind::kStop, 0.0, a, 0.0});
  stepper.poll(t += 1'000'000);
  const double end_rad = stepper.plan().angleAt(t);
  EXPECT_EQ(stepper.position(), static_cast<int64_t>(std::floor(end_rad / d)));
  const auto steps = seenSteps(gpio);
  int64_t net = 0;
  for (const auto& s : steps) net += s.direction;
  EXPECT_EQ(net, stepper.position());
  const TimingCheck check = checkStepTimes(steps, stepper.plan(), d);
  EXPECT_LT(check.max_error_ns, 1000.0L);
}

// Reversing (with inverted DIR wiring): DIR changes as soon as the next step's direction
// is known, at least dir_setup_ns before that STEP; STEP pulses keep their minimum widths.
TEST(GpioStepper, DirIsSetBeforeStepWithSetupTime) {
  GpioStepperOptions o = fakeOptions();
  o.lines.dir_positive_high = false;  // inverted wiring: DIR low turns positive
  VirtualClock clock(kT0Utime * 1000);
  FakeGpioBackend gpio(clock);
  GpioStepper stepper(o, gpio, clock, kT0Utime);
  const double d = o.stepRad();
  int64_t t = kT0Utime;
  for (int i = 0; i < 6; ++i) {
    stepper.command(t, moveBy((i % 2 == 0 ? 10 : -10) * d, 1.0, 1000.0));
    stepper.poll(t += 50'000);
  }
  const auto steps = seenSteps(gpio, false);
  ASSERT_EQ(steps.size(), 60u);
  for (size_t i = 0; i < steps.size(); ++i) {
    EXPECT_EQ(steps[i].direction, (i / 10) % 2 == 0 ? 1 : -1) << i;
    EXPECT_GE(steps[i].t_ns - steps[i].dir_set_ns, o.timing.dir_setup_ns) << i;
  }
  // Pulses: high for step_pulse_ns, then low at least as long.
  int64_t rise_ns = -1, fall_ns = -1;
  for (const auto& c : gpio.outputs()) {
    if (c.offset != kStep) continue;
    if (c.high) {
      if (fall_ns >= 0) {
        EXPECT_GE(c.t_ns - fall_ns, o.timing.step_pulse_ns);
      }
      rise_ns = c.t_ns;
    } else if (rise_ns >= 0) {
      EXPECT_GE(c.t_ns - rise_ns, o.timing.step_pulse_ns);
      fall_ns = c.t_ns;
    }
  }
  EXPECT_EQ(stepper.position(), 0);
}

class Homing : public ::testing::TestWithParam<double> {};

// Homing from either side of the switch: the controller takes the home edge's time from the
// switch (the kernel's stamp of the step that moved the sheet into the beam), so its
// reference, where it believes step position p lies (commanded - planned angle + p d), is
// the true one within one step. The shaft itself trails the plan by less than a step in
// the direction it turns (a step is made when the plan reaches it), so commanded and true
// angle differ by less than two steps at any time.
TEST_P(Homing, EndsAtTheEdgeWithinOneStep) {
  RotatingLidarConfig rig;
  rig.motor.mode = 1;
  ControllerRig r(rig, GetParam());
  EXPECT_EQ(r.stepper->switchBlocked(), GetParam() < 0);
  r.runUntil([&] { return r.controller.phase() == MotorController::Phase::kPositioning; }, 60);
  ASSERT_EQ(r.controller.phase(), MotorController::Phase::kPositioning);
  EXPECT_EQ(r.shaft.transitions(), GetParam() < 0 ? 2 : 1);
  EXPECT_EQ(r.controller.counter("homings"), 1);
  const double d = fakeOptions().stepRad();
  double worst = 0;
  for (int i = 0; i < 3000; ++i) {  // through positioning: 3 s
    Outbox out;
    r.controller.tick(r.now, out);
    worst = std::max(worst, std::abs(r.controller.commandedAngle(r.now) - r.shaft.angle()));
    r.now += 1000;
  }
  const ShaftTrajectory plan = r.stepper->plan();
  const double reference_error = r.controller.commandedAngle(r.now) - plan.angleAt(r.now) +
                                 double(r.stepper->position()) * d - r.shaft.angle();
  std::cout << "homing from " << (GetParam() < 0 ? "blocked" : "clear")
            << ": home reference off by " << reference_error / d
            << " steps, commanded - true angle at most " << worst / d << " steps\n";
  EXPECT_GE(reference_error, -1e-9);
  EXPECT_LT(reference_error, d);
  EXPECT_LT(worst, 2 * d);
}

INSTANTIATE_TEST_SUITE_P(BothSides, Homing,
                         ::testing::Values(kInitialUnblockedRad, kInitialBlockedRad));

// A contact that bounces (4 extra toggles within 0.8 ms, debounce 2 ms) still gives the
// controller one edge per real transition, dated at the first toggle.
TEST(GpioStepper, BouncingSwitchGivesOneEdgePerTransition) {
  RotatingLidarConfig rig;
  rig.motor.mode = 1;
  ControllerRig r(rig, kInitialBlockedRad, 4);
  r.runUntil([] { return false; }, 120);
  ASSERT_EQ(r.controller.phase(), MotorController::Phase::kDone);
  EXPECT_EQ(r.shaft.transitions(), 3);  // leave, seek, and off the sheet in the sweep
  EXPECT_EQ(r.controller.counter("switch_edges"), r.shaft.transitions());
  EXPECT_EQ(r.stepper->switchBlocked(), r.shaft.blocked());
}

TEST(SwitchDebouncer, BounceGlitchAndDebounceZero) {
  std::vector<DebouncedEdge> out;
  SwitchDebouncer d(false, 2'000'000);
  for (int i = 0; i < 5; ++i) d.onEdge(1'000'000 + i * 100'000, i % 2 == 0, out);  // ends high
  d.update(2'900'000, out);
  EXPECT_TRUE(out.empty());  // not yet stable for 2 ms
  d.update(3'400'000, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].t_ns, 1'000'000);
  EXPECT_TRUE(out[0].level);
  d.onEdge(10'000'000, false, out);  // a glitch back to high
  d.onEdge(10'300'000, true, out);
  d.update(20'000'000, out);
  EXPECT_EQ(out.size(), 1u);
  d.onEdge(30'000'000, false, out);  // stable change, accepted by the next edge
  d.onEdge(33'000'000, true, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].t_ns, 30'000'000);
  SwitchDebouncer none(false, 0);
  none.onEdge(5, true, out);
  none.update(5, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[2].t_ns, 5);
}

// Enable: requested at its disable level, enabled once every line is held, disabled again
// when the driver goes away; an active-high enable the other way round.
TEST(GpioStepper, EnableGoesToItsDisableLevelOnDestruction) {
  for (const bool active_low : {true, false}) {
    GpioStepperOptions o = fakeOptions();
    o.lines.enable_active_low = active_low;
    VirtualClock clock(kT0Utime * 1000);
    FakeGpioBackend gpio(clock);
    {
      GpioStepper stepper(o, gpio, clock, kT0Utime);
      EXPECT_EQ(gpio.outputLevel(kEnable), !active_low);
      stepper.command(kT0Utime, moveBy(0.5, 1.0, 10.0));
      stepper.poll(kT0Utime + 100'000);  // mid-move
    }
    EXPECT_EQ(gpio.outputLevel(kEnable), active_low);
    std::vector<bool> enable_levels;
    for (const auto& c : gpio.outputs()) {
      if (c.offset == kEnable) enable_levels.push_back(c.high);
    }
    EXPECT_EQ(enable_levels, (std::vector<bool>{active_low, !active_low, active_low}));
  }
}

// A crash (here SIGABRT) disables the driver from the signal handler, then the process dies
// of the signal as it would have.
TEST(GpioStepper, FatalSignalDisablesTheDriver) {
  VirtualClock clock(kT0Utime * 1000);
  FakeGpioBackend gpio(clock);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const rlimit no_core{0, 0};
    setrlimit(RLIMIT_CORE, &no_core);
    GpioStepper stepper(fakeOptions(), gpio, clock, kT0Utime);
    raise(SIGABRT);
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGABRT);
  char level = 0;
  ASSERT_EQ(read(gpio.signalPipeReadFd(), &level, 1), 1);
  EXPECT_EQ(level, 1);  // active-low enable: high disables
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(GpioStepper, BadUrisAndLinesAreOneClearError) {
  const DeviceUri u = parseDeviceUri("gpiod://gpiochip0?step=17&dir=27&enable=22&home=23");
  EXPECT_EQ(u.protocol, DeviceProtocol::kGpiod);
  EXPECT_EQ(u.gpio.chip, "gpiochip0");
  EXPECT_EQ(u.gpio.step, 17);
  EXPECT_EQ(u.gpio.home, 23);
  EXPECT_TRUE(u.gpio.enable_active_low);
  EXPECT_TRUE(u.gpio.home_blocked_high);
  EXPECT_EQ(u.gpio.home_pull, GpioPull::kUp);
  const DeviceUri v = parseDeviceUri(
      "gpiod:///dev/gpiochip4?step=0&dir=1&enable=2&home=3&enable_active=high&dir_positive=low&"
      "home_blocked=low&home_pull=none");
  EXPECT_EQ(v.gpio.chip, "/dev/gpiochip4");
  EXPECT_FALSE(v.gpio.enable_active_low);
  EXPECT_FALSE(v.gpio.dir_positive_high);
  EXPECT_FALSE(v.gpio.home_blocked_high);
  EXPECT_EQ(v.gpio.home_pull, GpioPull::kNone);
  for (const auto& [text, expected] : std::vector<std::pair<std::string, std::string>>{
           {"gpiod://gpiochip0?step=17&dir=27&enable=22", "missing line home"},
           {"gpiod://gpiochip0?step=17&dir=17&enable=22&home=23", "both 17"},
           {"gpiod://gpiochip0?step=70000&dir=27&enable=22&home=23",
            "bad line offset step '70000'"},
           {"gpiod://gpiochip0?step=-1&dir=27&enable=22&home=23", "bad line offset step"},
           {"gpiod://gpiochip0?step=x&dir=27&enable=22&home=23", "bad line offset step"},
           {"gpiod://gpiochip0?step=1&dir=2&enable=3&home=4&home_pull=sideways", "home_pull"},
           {"gpiod://gpiochip0?step=1&dir=2&enable=3&home=4&speed=9", "unknown option"},
           {"gpiod://?step=1&dir=2&enable=3&home=4", "expected gpiod://CHIP"}}) {
    const std::string e = errorOf([&] { parseDeviceUri(text); });
    EXPECT_NE(e.find("device '" + text + "': "), std::string::npos) << e;
    EXPECT_NE(e.find(expected), std::string::npos) << text << ": " << e;
  }
  EXPECT_NE(errorOf([] {
              parseDeviceUriFor("scip://host", {DeviceProtocol::kGpiod});
            }).find("does not belong here"),
            std::string::npos);

  // A line the chip does not have, a busy line: GpioError naming chip, line and errno text.
  VirtualClock clock(kT0Utime * 1000);
  GpioStepperOptions o = fakeOptions();
  o.lines.home = 60;
  {
    FakeGpioBackend gpio(clock);
    const std::string e = errorOf([&] { GpioStepper s(o, gpio, clock, kT0Utime); });
    EXPECT_NE(e.find("GPIO chip 'fake-gpiochip' line 60 (home switch): not on this chip"),
              std::string::npos)
        << e;
    EXPECT_NE(e.find(std::strerror(EINVAL)), std::string::npos) << e;
    EXPECT_EQ(gpio.outputLevel(kEnable), true);  // requested disabled, left disabled
  }
  {
    FakeGpioBackend gpio(clock);
    gpio.makeBusy(kEnable);
    const std::string e = errorOf([&] { GpioStepper s(fakeOptions(), gpio, clock, kT0Utime); });
    EXPECT_NE(e.find("line 22 (enable): cannot request it: " + std::string(std::strerror(EBUSY))),
              std::string::npos)
        << e;
  }
}

// The dedicated thread on the real clock (nothing here depends on how punctual it is): it
// makes the commanded steps on its own; when a write fails it stops, poll() reports it
// as a GpioError and the driver is disabled.
TEST(GpioStepper, StepThreadMakesTheStepsAndStopsOnAWriteError) {
  GpioStepperOptions o = fakeOptions();
  o.dedicated_thread = true;
  MonotonicClock clock;
  FakeGpioBackend gpio(clock);
  const auto poll_until = [&](GpioStepper& stepper, const std::function<bool()>& done) {
    for (int i = 0; i < 5000 && !done(); ++i) {
      stepper.poll(clock.nowNs() / 1000);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return done();
  };
  GpioStepper stepper(o, gpio, clock, clock.nowNs() / 1000);
  stepper.command(clock.nowNs() / 1000, moveBy(-40 * o.stepRad(), 2.0, 200.0));
  ASSERT_TRUE(poll_until(stepper, [&] { return stepper.position() == -40; }));
  const auto steps = seenSteps(gpio);
  ASSERT_EQ(steps.size(), 40u);
  for (const auto& s : steps) {
    EXPECT_EQ(s.direction, -1);
    EXPECT_GE(s.t_ns - s.dir_set_ns, o.timing.dir_setup_ns);
  }
  EXPECT_TRUE(stepper.fault().empty());
  gpio.failWrites(kStep);
  stepper.command(clock.nowNs() / 1000, moveBy(40 * o.stepRad(), 2.0, 200.0));
  ASSERT_TRUE(poll_until(stepper, [&] { return !stepper.fault().empty(); }));
  EXPECT_NE(stepper.fault().find("line 17 (output): cannot set it"), std::string::npos);
  const std::string e = errorOf([&] { stepper.poll(clock.nowNs() / 1000); });
  EXPECT_NE(e.find("step generator stopped"), std::string::npos) << e;
  EXPECT_EQ(gpio.outputLevel(kEnable), true);  // disabled
}

// The real backend, without hardware: a chip that is not there is one clear error.
TEST(GpiodBackend, MissingChipIsOneClearError) {
  const std::string e = errorOf([] { openGpiodChip("gpiochip77"); });
  std::cout << "libgpiod: " << e << "\n";
  EXPECT_NE(e.find("GPIO chip 'gpiochip77': cannot open it: "), std::string::npos) << e;
  EXPECT_NE(e.find(std::strerror(ENOENT)), std::string::npos) << e;
  EXPECT_NE(errorOf([] { openGpiodChip("/dev/gpiochip-none"); }).find("/dev/gpiochip-none"),
            std::string::npos);
}

// The rig file's motor keys: every bad value names the file and the key.
TEST(GpioStepper, MotorKeysAreValidated) {
  const std::string rig = std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_a.yaml";
  const RotatingLidarConfig ok = loadRotatingLidarConfig(rig, {});
  EXPECT_EQ(ok.motor.device, "sim");
  EXPECT_EQ(ok.motor.steps_per_rev, 200);
  EXPECT_EQ(ok.motor.microsteps, 16);
  const auto configError = [&](const std::string& set) {
    return errorOf([&] { loadRotatingLidarConfig(rig, {set}); });
  };
  for (const auto& [set, key] : std::vector<std::pair<std::string, std::string>>{
           {"motor.steps_per_rev=0", "motor.steps_per_rev"},
           {"motor.microsteps=3", "motor.microsteps"},
           {"motor.microsteps=0", "motor.microsteps"},
           {"motor.switch_debounce_ms=-1", "motor.switch_debounce_ms"},
           {"motor.device=gpiod://gpiochip0?step=1", "motor.device"},
           {"motor.device=scip://10.0.0.1", "motor.device"},
           {"motor.steps_per_rev=100000", "motor.microsteps"}}) {
    const std::string e = configError(set);
    EXPECT_NE(e.find(rig + ": key '" + key + "'"), std::string::npos) << set << ": " << e;
  }
  const GpioStepperOptions o = gpioStepperOptions(
      loadRotatingLidarConfig(rig, {"motor.device=gpiod://gpiochip0?step=17&dir=27&enable=22&"
                                    "home=23&enable_active=high",
                                    "motor.microsteps=8", "motor.switch_debounce_ms=0.5"})
          .motor);
  EXPECT_EQ(o.lines.enable, 22);
  EXPECT_FALSE(o.lines.enable_active_low);
  EXPECT_EQ(o.microsteps, 8);
  EXPECT_EQ(o.debounce_ns, 500'000);
  EXPECT_NEAR(o.stepRad(), 2 * M_PI / 1600, 1e-15);
}

}  // namespace
}  // namespace sweepmap
