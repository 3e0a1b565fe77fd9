// sweepmap-profiler (rig C): drives the turntable through its sweeps and publishes the
// profile sensor's raw profiles on PROFILE (processes/profile_scan_node.hpp). The devices
// are the rig's profiler.device and turntable.device: `sim` (or --sim), the simulated rig C
// (sim/profile_devices.hpp), which also publishes TRUTH_PROFILE_RIG. No real-device
// driver exists yet (no protocol chosen): another device is a config error.
#include <lcm/lcm-cpp.hpp>

#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "processes/profile_scan_node.hpp"
#include "sim/profile_devices.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-profiler (rotating_profile rigs, Zhao 2021): turns the turntable from "
      "turntable.sweep_start_deg to sweep_end_deg at speed_deg_s once per sweep (back to the "
      "start and --pause-s between sweeps, for the plate to be moved) and publishes every "
      "profile exposed during a sweep raw on PROFILE, one per message, with the encoder count "
      "latched at its exposure and the sweep's number; its counters on STATUS_PROFILER. "
      "Devices: profiler.device and turntable.device (sim: the simulated rig C, which "
      "publishes TRUTH_PROFILE_RIG when a plate pose is put in place)"};
  CommonOptions common;
  bool sim = false;
  uint64_t seed = 1;
  ProfileScanOptions options;
  addCommonOptions(app, common, {RigKind::kRotatingProfile});
  app.add_flag("--sim", sim, "the simulated sensor and turntable whatever the rig file says");
  app.add_option("--seed", seed, "simulation seed")->capture_default_str();
  app.add_option("--sweeps", options.sweeps, "sweeps to make, then exit (0 = until stopped)")
      ->capture_default_str()
      ->check(atLeast(0));
  app.add_option("--pause-s", options.pause_s,
                 "pause at the start angle before every sweep but the first [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 3600.0));
  if (const auto code = parseCommandLine(app, argc, argv)) return *code;
  const std::optional<Rig> loaded = loadRigOrReport(common);
  if (!loaded) return kExitUsage;
  const auto* rig = rigOfKindOrReport<RotatingProfileConfig>(*loaded, "sweepmap-profiler");
  if (!rig) return kExitUsage;
  if (!sim && (rig->profiler.device != "sim" || rig->turntable.device != "sim")) {
    std::cerr << "sweepmap-profiler: no driver for profiler.device '" << rig->profiler.device
              << "' / turntable.device '" << rig->turntable.device << "' (only sim)\n";
    return kExitUsage;
  }
  std::unique_ptr<SimProfileWorld> world;
  try {
    world = std::make_unique<SimProfileWorld>(rig->profiler, rig->turntable, rig->sim, seed,
                                              wallUtime());
  } catch (const std::exception& e) {
    std::cerr << "config error: " << e.what() << "\n";
    return kExitUsage;
  }
  SimTurntable table(world.get());
  SimProfilerDevice sensor(world.get());
  ProfileScanNode node(rig->profiler, rig->turntable, &table, &sensor, options);
  ProfileTruthNode truth(world.get());
  lcm::LCM lcm(common.lcm_url);
  installStopSignals();
  LiveOptions live = liveOptions(common);
  live.should_stop = [&node] { return node.done() || node.failed(); };
  const int rc = runLive(lcm, {&truth, &node}, live);
  if (rc != 0) return rc;
  return node.failed() ? kExitDeviceIo : kExitOk;
}
