// sweepmap-mapper: SWEEP_CLOUD -> OctoMap, MAP_STATS; saves .bt on MAP_SAVE and at exit.
#include <lcm/lcm-cpp.hpp>

#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "processes/mapper_node.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-mapper: inserts assembled sweeps (rotating_lidar rigs) or world-frame "
      "scans (mobile_lidar rigs) or profiles (rotating_profile rigs), in mapper.batch_s "
      "batches, "
      "into an OctoMap OcTree, publishes MAP_STATS, saves the map (.bt, atomically) on "
      "MAP_SAVE and on shutdown"};
  CommonOptions common;
  std::string save_path = "map.bt";
  addCommonOptions(app, common);
  app.add_option("--save", save_path, "map file written at shutdown and on empty MAP_SAVE")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const std::optional<Rig> rig = loadRigOrReport(common);
  if (!rig) return 2;
  const MapperConfig config = std::visit([](const auto& c) { return c.mapper; }, rig->config);

  lcm::LCM lcm(common.lcm_url);
  MapperNode node(config, save_path);
  installStopSignals();
  return runLive(lcm, {&node}, LiveOptions{});
}
