// sweepmap-motor: homing and 3D sweeps of the stepper; MOTOR_STATE, MOTOR_SWITCH, SCAN_WINDOW.
#include <lcm/lcm-cpp.hpp>

#include "drivers/sim_stepper.hpp"
#include "processes/channels.hpp"
#include "processes/cli_common.hpp"
#include "processes/convert.hpp"
#include "processes/live_runner.hpp"
#include "processes/motor_controller.hpp"
#include "processes/sim_setup.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-motor: drives the encoder-less stepper (homing on the photoelectric "
      "switch, the 7 scan modes, the improved action sequence of Yuan 2021 Fig. 2) and "
      "publishes MOTOR_STATE, MOTOR_SWITCH and SCAN_WINDOW"};
  CommonOptions common;
  bool sim = false;
  uint64_t seed = 1;
  int sweeps = 0;
  addCommonOptions(app, common);
  app.add_flag("--sim", sim, "use the simulated stepper and switch (publishes TRUTH_SHAFT)");
  app.add_option("--seed", seed, "simulation seed")->capture_default_str();
  app.add_option("--sweeps", sweeps, "sweeps to make, then exit (0 = until stopped)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const std::optional<Rig> loaded = loadRigOrReport(common);
  if (!loaded) return 2;
  const auto* rig_config = rigOfKindOrReport<RotatingLidarConfig>(*loaded, "sweepmap-motor");
  if (!rig_config) return 2;
  const RotatingLidarConfig& rig = *rig_config;
  if (!sim) {
    std::cerr << "sweepmap-motor: no real stepper driver is built yet; use --sim\n";
    return 2;
  }

  lcm::LCM lcm(common.lcm_url);
  const int64_t start = wallUtime();
  SimStepper stepper(rig.motor, rig.sim, stepperSeed(seed), kSimInitialShaftAngleRad, start,
                     [&lcm](const ShaftSegment& s) {
                       const truth_shaft_t m = toLcm(s, wallUtime());
                       lcm.publish(channels::kTruthShaft, &m);
                     });
  MotorController controller(rig, &stepper, sweeps, start);
  installStopSignals();
  LiveOptions options;
  options.should_stop = [&] { return controller.done(); };
  const int rc = runLive(lcm, {&controller}, options);
  return rc != 0 ? rc : (controller.phase() == MotorController::Phase::kFault ? 1 : 0);
}
