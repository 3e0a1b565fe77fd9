// sweepmap-lidar: publishes raw scans on LIDAR_SCAN.
#include <lcm/lcm-cpp.hpp>

#include "drivers/scene.hpp"
#include "drivers/sim_lidar.hpp"
#include "processes/channels.hpp"
#include "processes/cli_common.hpp"
#include "processes/lidar_node.hpp"
#include "processes/live_runner.hpp"
#include "processes/sim_setup.hpp"
#include "processes/truth_sweep_node.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-lidar: publishes the lidar's raw 2D scans with their timing on "
      "LIDAR_SCAN"};
  CommonOptions common;
  bool sim = false;
  std::string scene_path;
  uint64_t seed = 1;
  addCommonOptions(app, common);
  app.add_flag("--sim", sim, "simulated lidar in a simulated scene (follows TRUTH_SHAFT)");
  app.add_option("--scene", scene_path,
                 "scene file or name for --sim (default: scene_conference_room)");
  app.add_option("--seed", seed, "simulation seed")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const std::optional<Rig> loaded = loadRigOrReport(common);
  if (!loaded) return 2;
  const auto* rig_config = rigOfKindOrReport<RotatingLidarConfig>(*loaded, "sweepmap-lidar");
  if (!rig_config) return 2;
  const RotatingLidarConfig& rig = *rig_config;
  if (!sim) {
    std::cerr << "sweepmap-lidar: no real lidar driver is built yet; use --sim\n";
    return 2;
  }
  if (scene_path.empty()) scene_path = defaultSceneName(loaded->kind());
  SceneConfig scene_config;
  try {
    scene_config = loadScene(resolveConfigFile(scene_path));
  } catch (const std::exception& e) {
    std::cerr << "config error: " << e.what() << "\n";
    return 2;
  }
  const Scene scene(scene_config, rig.plate);

  lcm::LCM lcm(common.lcm_url);
  ShaftTrajectory truth;
  SimLidar device(rig.lidar, rig.sim, rig.plate, scene, &truth, lidarSeed(seed), wallUtime());
  TruthFollowerNode follower(&truth);
  LidarNode node(rig.lidar, &device);
  TruthSweepNode truth_sweep(&truth, rig.sim.alpha_true_deg * M_PI / 180.0);
  const truth_rig_t truth_rig = makeTruthRig(rig, scene_config, scene, wallUtime());
  lcm.publish(channels::kTruthRig, &truth_rig);
  installStopSignals();
  return runLive(lcm, {&follower, &node, &truth_sweep}, LiveOptions{});
}
