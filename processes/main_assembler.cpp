// sweepmap-assembler: rig A: LIDAR_SCAN + SCAN_WINDOW -> SWEEP_CLOUD (chunks) + SWEEP_STATUS;
// rig B (--rig-b): LIDAR_SCAN + ODOMETRY_POSE -> SWEEP_CLOUD (one world-frame chunk per scan).
#include <lcm/lcm-cpp.hpp>

#include <memory>

#include "processes/assembler_node.hpp"
#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "processes/world_assembler_node.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{"sweepmap-assembler: rig A (--rig): builds 3D sweeps from the scans of each lidar "
               "window, corrects their attitude with the triangular plate (Yuan 2021 Eq. 4-10) and "
               "publishes them in chunks on SWEEP_CLOUD. Rig B (--rig-b): transforms every scan "
               "to the world frame with the pose (assembler.pose_channel) interpolated at each "
               "ray's time and the mounting (Miao 2022 Eq. 11-14), one chunk per scan"};
  CommonOptions common;
  addRigAOrBOptions(app, common);
  CLI11_PARSE(app, argc, argv);
  std::unique_ptr<Node> node;
  if (!common.rig_b_path.empty()) {
    const RigBConfig rig = loadRigBOrExit(common);
    node = std::make_unique<WorldAssemblerNode>(rig.assembler, rig.mounting.toMounting());
  } else {
    node = std::make_unique<AssemblerNode>(loadRigOrExit(common));
  }
  lcm::LCM lcm(common.lcm_url);
  installStopSignals();
  return runLive(lcm, {node.get()}, LiveOptions{});
}
