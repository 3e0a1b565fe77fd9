// sweepmap-assembler: LIDAR_SCAN + SCAN_WINDOW -> SWEEP_CLOUD (chunks) + SWEEP_STATUS.
#include <lcm/lcm-cpp.hpp>

#include "processes/assembler_node.hpp"
#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{"sweepmap-assembler: builds 3D sweeps from the scans of each lidar window, "
               "corrects their attitude with the triangular plate (Yuan 2021 Eq. 4-10) and "
               "publishes them in chunks on SWEEP_CLOUD"};
  CommonOptions common;
  addCommonOptions(app, common);
  CLI11_PARSE(app, argc, argv);
  const RigConfig rig = loadRigOrExit(common);

  lcm::LCM lcm(common.lcm_url);
  AssemblerNode node(rig);
  installStopSignals();
  return runLive(lcm, {&node}, LiveOptions{});
}
