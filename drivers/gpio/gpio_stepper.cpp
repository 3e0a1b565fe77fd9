#include "drivers/gpio/gpio_stepper.hpp"

#include <cmath>
#include <stdexcept>

#include "drivers/gpio/fatal_signal_guard.hpp"

namespace sweepmap {
namespace {

int64_t floorDiv(int64_t a, int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

// Requests every line (ENABLE at its disable level first, STEP low, DIR positive, the home
// input) and returns the home input's level. Runs before the generator exists.
bool requestLines(const GpioStepperOptions& o, GpioBackend& gpio) {
  const GpioLines& l = o.lines;
  gpio.requestOutput(l.enable, l.enable_active_low, "enable");
  gpio.requestOutput(l.step, false, "step");
  gpio.requestOutput(l.dir, l.dir_positive_high, "dir");
  gpio.requestInput(l.home, l.home_pull, "home switch");
  return gpio.inputLevel(l.home);
}

}  // namespace

double GpioStepperOptions::stepRad() const {
  return 2.0 * M_PI / (double(steps_per_rev) * microsteps);
}

GpioStepperOptions gpioStepperOptions(const MotorConfig& motor) {
  const DeviceUri uri = parseDeviceUriFor(motor.device, {DeviceProtocol::kGpiod});
  if (uri.protocol != DeviceProtocol::kGpiod) {
    throw std::invalid_argument("motor.device '" + motor.device + "' is not a gpiod:// device");
  }
  GpioStepperOptions o;
  o.lines = uri.gpio;
  o.steps_per_rev = motor.steps_per_rev;
  o.microsteps = motor.microsteps;
  o.debounce_ns = std::llround(motor.switch_debounce_ms * 1e6);
  return o;
}

GpioStepper::GpioStepper(const GpioStepperOptions& options, GpioBackend& gpio, StepClock& clock,
                         int64_t start_utime)
    : options_(options),
      gpio_(gpio),
      debouncer_(blockedAt(requestLines(options, gpio)), options.debounce_ns),
      generator_(gpio, {options.lines.step, options.lines.dir, options.lines.dir_positive_high},
                 options.timing, clock, options.stepRad(), start_utime,
                 options.utime_ns_minus_clock_ns) {
  const GpioLines& l = options_.lines;
  fatal_slot_ = registerFatalSignalWrite(gpio_.signalSafeWrite(l.enable, l.enable_active_low));
  gpio_.setOutput(l.enable, !l.enable_active_low);
  generator_.setOnStep(options_.on_step);
  if (options_.dedicated_thread) generator_.start(options_.realtime_priority);
}

GpioStepper::~GpioStepper() {
  generator_.stop();
  try {
    disable();
  } catch (const std::exception&) {
    // The fatal-signal path and the wiring's pull are what is left; nothing to report to.
  }
  unregisterFatalSignalWrite(fatal_slot_);
}

void GpioStepper::disable() {
  gpio_.setOutput(options_.lines.enable, options_.lines.enable_active_low);
}

void GpioStepper::command(int64_t now_utime, const StepperCommand& cmd) {
  generator_.command(now_utime, cmd);
}

std::vector<SwitchEdge> GpioStepper::poll(int64_t now_utime) {
  if (options_.dedicated_thread) {
    if (const std::string fault = generator_.fault(); !fault.empty()) {
      disable();
      throw GpioError("step generator stopped: " + fault);
    }
  } else {
    generator_.runUntil(now_utime);
  }
  std::vector<DebouncedEdge> accepted;
  for (const GpioInputEvent& e : gpio_.readEvents(options_.lines.home)) {
    debouncer_.onEdge(e.monotonic_ns, blockedAt(e.rising), accepted);
  }
  debouncer_.update(now_utime * 1000 - options_.utime_ns_minus_clock_ns, accepted);
  std::vector<SwitchEdge> edges;
  for (const DebouncedEdge& e : accepted) {
    edges.push_back({floorDiv(e.t_ns + options_.utime_ns_minus_clock_ns, 1000), e.level});
  }
  return edges;
}

}  // namespace sweepmap
