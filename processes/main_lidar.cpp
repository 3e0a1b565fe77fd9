// sweepmap-lidar: opens the lidar the rig file names (lidar.device) or --device, and
// publishes its raw scans on LIDAR_SCAN with the driver's counters on STATUS_LIDAR.
#include <lcm/lcm-cpp.hpp>

#include "core/device_uri.hpp"
#include "drivers/real_lidar.hpp"
#include "processes/channels.hpp"
#include "processes/cli_common.hpp"
#include "processes/lidar_node.hpp"
#include "processes/live_runner.hpp"
#include "processes/message_codec.hpp"
#include "processes/sim_car.hpp"
#include "processes/sim_setup.hpp"
#include "processes/truth_sweep_node.hpp"
#include "sim/car_devices.hpp"
#include "sim/lidar.hpp"
#include "sim/scene.hpp"

namespace sweepmap {
namespace {

// The simulated X4 of a mobile rig on the simulated car (the car sweepmap-odometry --sim
// simulates, given the same seed and start time).
int runSimulatedCar(const CommonOptions& common, const Rig& loaded, const std::string& scene_name,
                    uint64_t seed, int64_t start_utime) {
  MobileLidarConfig rig = std::get<MobileLidarConfig>(loaded.config);
  std::unique_ptr<SimMobile> car;
  std::unique_ptr<Scene> scene;
  try {
    prepareSimMobileConfig(loaded.path, &rig);
    scene = std::make_unique<Scene>(
        loadScene(
            resolveSceneFile(scene_name.empty() ? defaultSceneName(loaded.kind()) : scene_name)),
        PlateConfig{});
    car = makeSimCar(rig, *scene, seed, start_utime > 0 ? start_utime : wallUtime());
  } catch (const std::exception& e) {
    std::cerr << "config error: " << e.what() << "\n";
    return kExitUsage;
  }
  lcm::LCM lcm(common.lcm_url);
  SimCarLidar device(car.get());
  LidarNode node(rig.lidar, &device);
  installStopSignals();
  return runLive(lcm, {&node}, liveOptions(common));
}

// The simulated UST-10LX of a rotating rig, following the simulated shaft (TRUTH_SHAFT).
int runSimulated(const CommonOptions& common, const Rig& loaded, const std::string& scene_name,
                 uint64_t seed) {
  const auto* rig_config =
      rigOfKindOrReport<RotatingLidarConfig>(loaded, "sweepmap-lidar --device sim");
  if (!rig_config) return kExitUsage;
  const RotatingLidarConfig& rig = *rig_config;
  const std::string scene_path = scene_name.empty() ? defaultSceneName(loaded.kind()) : scene_name;
  SceneConfig scene_config;
  try {
    scene_config = loadScene(resolveSceneFile(scene_path));
  } catch (const std::exception& e) {
    std::cerr << "config error: " << e.what() << "\n";
    return kExitUsage;
  }
  const Scene scene(scene_config, rig.plate);
  lcm::LCM lcm(common.lcm_url);
  ShaftTrajectory truth;
  SimLidar device(rig.lidar, rig.sim, rig.plate, scene, &truth, lidarSeed(seed), wallUtime());
  TruthFollowerNode follower(&truth);
  LidarNode node(rig.lidar, &device);
  TruthSweepNode truth_sweep(&truth, rig.sim.alpha_true_deg * M_PI / 180.0);
  const truth_rig_t truth_rig = makeTruthRig(rig, scene_config, scene, wallUtime());
  const truth_rig_errors_t truth_errors = makeTruthRigErrors(rig.sim, wallUtime());
  publishAll(lcm,
             {Message{truth_rig.utime, channels::kTruthRig, encodeMessage(truth_rig)},
              Message{truth_errors.utime, channels::kTruthRigErrors, encodeMessage(truth_errors)}},
             common.auth.get());
  installStopSignals();
  return runLive(lcm, {&follower, &node, &truth_sweep}, liveOptions(common));
}

// A real lidar: the driver's worker thread reads the device, the node publishes.
int runDevice(const CommonOptions& common, const LidarConfig& lidar, const DeviceUri& uri) {
  lcm::LCM lcm(common.lcm_url);
  if (!lcm.good()) {
    std::cerr << "sweepmap-lidar: cannot open LCM at '" << common.lcm_url << "'\n";
    return kExitDeviceIo;
  }
  std::unique_ptr<RealLidar> device = makeRealLidar(uri, lidar, RealLidarOptions{}, wallUtime);
  LidarNode node(lidar, device.get());
  device->start();
  installStopSignals();
  LiveOptions options = liveOptions(common);
  options.should_stop = [&node] { return node.failed(); };
  options.healthy = [&device] { return !device->workerStalled(kDeviceWorkerStallMs); };
  const int rc = runLive(lcm, {&node}, options);
  // A device that is not the one the rig file describes: a configuration error, not a
  // crash to restart from.
  return node.failed() ? kExitDeviceIdentity : rc;
}

}  // namespace
}  // namespace sweepmap

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-lidar: opens the lidar (the rig file's lidar.device, or --device) and publishes "
      "its raw 2D scans with their timing on LIDAR_SCAN; the driver's counters (checksum "
      "errors, resyncs, timeouts, reconnects, clock resets) and last error on STATUS_LIDAR"};
  CommonOptions common;
  std::string device;
  bool sim = false;
  std::string scene_path;
  uint64_t seed = 1;
  addCommonOptions(app, common, {RigKind::kRotatingLidar, RigKind::kMobileLidar});
  app.add_option("--device", device,
                 "the lidar, overriding lidar.device: sim | scip://HOST[:PORT] (Hokuyo "
                 "UST-10LX/20LX, SCIP 2.0 over TCP) | ydlidar:///dev/PORT (YDLIDAR X4) | "
                 "rplidar:///dev/PORT[?baud=N] (RPLIDAR A1/A2)");
  app.add_flag("--sim", sim,
               "same as --device sim: the simulated lidar (rotating rigs: it follows "
               "TRUTH_SHAFT; mobile rigs: on the simulated car)");
  app.add_option("--scene", scene_path,
                 "scene file or name for the simulated lidar (default: the rig kind's scene)");
  app.add_option("--seed", seed, "simulation seed")->capture_default_str();
  int64_t sim_start_utime = 0;
  app.add_option("--sim-start-utime", sim_start_utime,
                 "mobile rigs: when the simulated car starts [us, wall clock]; 0 = now (give "
                 "sweepmap-odometry --sim the same)");
  if (const auto code = parseCommandLine(app, argc, argv)) return *code;
  const std::optional<Rig> loaded = loadRigOrReport(common);
  if (!loaded) return kExitUsage;
  if (sim) device = "sim";
  DeviceUri uri;
  try {
    uri = parseDeviceUri(device.empty() ? loaded->lidar().device : device);
  } catch (const std::exception& e) {  // a bad URI, or a rig without a 2D lidar (rig C)
    std::cerr << "sweepmap-lidar: " << e.what() << "\n";
    return kExitUsage;
  }
  if (uri.protocol == DeviceProtocol::kSim) {
    if (loaded->kind() == RigKind::kMobileLidar) {
      return runSimulatedCar(common, *loaded, scene_path, seed, sim_start_utime);
    }
    return runSimulated(common, *loaded, scene_path, seed);
  }
  return runDevice(common, loaded->lidar(), uri);
}
