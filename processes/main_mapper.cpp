// sweepmap-mapper: SWEEP_CLOUD -> OctoMap, MAP_STATS; saves .bt on MAP_SAVE and at exit.
#include <lcm/lcm-cpp.hpp>

#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "processes/mapper_node.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{"sweepmap-mapper: inserts assembled sweeps (rig A) or world-frame scans (rig B) "
               "into an OctoMap OcTree, publishes MAP_STATS, saves the map (.bt, atomically) on "
               "MAP_SAVE and on shutdown"};
  CommonOptions common;
  std::string save_path = "map.bt";
  addRigAOrBOptions(app, common);
  app.add_option("--save", save_path, "map file written at shutdown and on empty MAP_SAVE")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const MapperConfig config =
      common.rig_b_path.empty() ? loadRigOrExit(common).mapper : loadRigBOrExit(common).mapper;

  lcm::LCM lcm(common.lcm_url);
  MapperNode node(config, save_path);
  installStopSignals();
  return runLive(lcm, {&node}, LiveOptions{});
}
