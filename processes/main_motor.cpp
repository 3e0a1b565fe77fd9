// sweepmap-motor: homing and 3D sweeps of the stepper; MOTOR_STATE, MOTOR_SWITCH, SCAN_WINDOW.
// The stepper is motor.device: sim (or --sim) the simulated stepper and switch, gpiod://...
// the real one on GPIO lines (drivers/gpio/gpio_stepper.hpp).
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "drivers/gpio/gpio_stepper.hpp"
#include "drivers/gpio/gpiod_backend.hpp"
#include "processes/channels.hpp"
#include "processes/cli_common.hpp"
#include "processes/convert.hpp"
#include "processes/live_runner.hpp"
#include "processes/motor_controller.hpp"
#include "processes/sim_setup.hpp"
#include "sim/stepper.hpp"

namespace sweepmap {
namespace {

// `device_fault`: why the device can no longer move the motor ("" while it can); the
// process then stops with status 1.
int runController(
    lcm::LCM& lcm, const RotatingLidarConfig& rig, StepperDevice& stepper, int sweeps,
    int64_t start, LiveOptions options,
    const std::function<std::string()>& device_fault = [] { return std::string(); }) {
  MotorController controller(rig, &stepper, sweeps, start);
  installStopSignals();
  options.should_stop = [&] { return controller.done() || !device_fault().empty(); };
  const int rc = runLive(lcm, {&controller}, options);
  if (rc != 0) return rc;
  if (const std::string fault = device_fault(); !fault.empty()) {
    std::cerr << "sweepmap-motor: the stepper stopped: " << fault << "\n";
    return kExitDeviceIo;
  }
  return controller.phase() == MotorController::Phase::kFault ? kExitDeviceIo : kExitOk;
}

int runSim(const RotatingLidarConfig& rig, const CommonOptions& common, uint64_t seed, int sweeps) {
  lcm::LCM lcm(common.lcm_url);
  const int64_t start = wallUtime();
  SimStepper stepper(rig.motor, rig.sim, stepperSeed(seed), kSimInitialShaftAngleRad, start,
                     [&lcm, &common](const ShaftSegment& s) {
                       // Signed as everything else (with --key-file): the simulated lidar
                       // follows the shaft from it, and drops what is unsigned.
                       const truth_shaft_t m = toLcm(s, wallUtime());
                       publishAll(lcm, {Message{m.utime, channels::kTruthShaft, encodeMessage(m)}},
                                  common.auth.get());
                     });
  return runController(lcm, rig, stepper, sweeps, start, liveOptions(common));
}

// The real stepper: a chip or line that cannot be had is one message and exit status 1.
int runGpio(const RotatingLidarConfig& rig, const CommonOptions& common, int sweeps) {
  GpioStepperOptions options = gpioStepperOptions(rig.motor);
  options.utime_ns_minus_clock_ns = wallMinusMonotonicNs();
  std::unique_ptr<GpioBackend> gpio;
  MonotonicClock clock;
  std::unique_ptr<GpioStepper> stepper;
  const int64_t start = wallUtime();
  try {
    gpio = openGpiodChip(options.lines.chip);
    stepper = std::make_unique<GpioStepper>(options, *gpio, clock, start);
  } catch (const GpioError& e) {
    std::cerr << "sweepmap-motor: " << e.what() << "\n";
    return kExitDeviceIo;
  }
  std::cerr << "sweepmap-motor: " << rig.motor.device << ", step thread "
            << (stepper->realtime() ? "SCHED_FIFO" : "at normal priority (no SCHED_FIFO)") << "\n";
  lcm::LCM lcm(common.lcm_url);
  return runController(lcm, rig, *stepper, sweeps, start, liveOptions(common),
                       [&] { return stepper->fault(); });
}

}  // namespace
}  // namespace sweepmap

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-motor: drives the encoder-less stepper (homing on the photoelectric "
      "switch, the 7 scan modes, the improved action sequence of Yuan 2021 Fig. 2) and "
      "publishes MOTOR_STATE, MOTOR_SWITCH and SCAN_WINDOW. The stepper is the rig's "
      "motor.device: sim, or gpiod://CHIP?step=N&dir=N&enable=N&home=N for the real one on "
      "GPIO lines"};
  CommonOptions common;
  bool sim = false;
  uint64_t seed = 1;
  int sweeps = 0;
  addCommonOptions(app, common, {RigKind::kRotatingLidar});
  app.add_flag("--sim", sim,
               "use the simulated stepper and switch whatever motor.device says (publishes "
               "TRUTH_SHAFT)");
  app.add_option("--seed", seed, "simulation seed")->capture_default_str();
  app.add_option("--sweeps", sweeps, "sweeps to make, then exit (0 = until stopped)")
      ->capture_default_str();
  if (const auto code = parseCommandLine(app, argc, argv)) return *code;
  const std::optional<Rig> loaded = loadRigOrReport(common);
  if (!loaded) return kExitUsage;
  const auto* rig_config = rigOfKindOrReport<RotatingLidarConfig>(*loaded, "sweepmap-motor");
  if (!rig_config) return kExitUsage;
  const RotatingLidarConfig& rig = *rig_config;
  if (sim || parseDeviceUri(rig.motor.device).protocol == DeviceProtocol::kSim) {
    return runSim(rig, common, seed, sweeps);
  }
  return runGpio(rig, common, sweeps);
}
