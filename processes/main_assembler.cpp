// sweepmap-assembler, by the rig's kind: rotating_lidar: LIDAR_SCAN + SCAN_WINDOW ->
// SWEEP_CLOUD (chunks) + SWEEP_STATUS; mobile_lidar: LIDAR_SCAN + ODOMETRY_POSE ->
// SWEEP_CLOUD (one world-frame chunk per scan); rotating_profile: PROFILE -> SWEEP_CLOUD (one
// chunk per profile in frame O_r, Zhao 2021 Eq. 7 generalised).
#include <lcm/lcm-cpp.hpp>
#include <memory>

#include "processes/assembler_node.hpp"
#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "processes/profile_assembler_node.hpp"
#include "processes/world_assembler_node.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-assembler: what it assembles follows the rig's kind. rotating_lidar: "
      "builds 3D sweeps from the scans of each lidar window, corrects their attitude "
      "with the triangular plate (Yuan 2021 Eq. 4-10) and publishes them in chunks on "
      "SWEEP_CLOUD. mobile_lidar: transforms every scan to the world frame with the "
      "pose (assembler.pose_channel) interpolated at each ray's time and the mounting "
      "(Miao 2022 Eq. 11-14), one chunk per scan. rotating_profile: places every PROFILE "
      "in the turntable's frame O_r by Zhao 2021 Eq. 7 (generalised with the laser plane's "
      "tilt and the encoder's zero) with the rig's geometry (geometry.*, or its calibration "
      "file), one chunk per profile"};
  CommonOptions common;
  addCommonOptions(app, common,
                   {RigKind::kRotatingLidar, RigKind::kMobileLidar, RigKind::kRotatingProfile});
  if (const auto code = parseCommandLine(app, argc, argv)) return *code;
  const std::optional<Rig> rig = loadRigOrReport(common);
  if (!rig) return kExitUsage;
  const std::unique_ptr<Node> node = std::visit(
      [](const auto& c) -> std::unique_ptr<Node> {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, RotatingLidarConfig>) {
          return std::make_unique<AssemblerNode>(c);
        } else if constexpr (std::is_same_v<T, MobileLidarConfig>) {
          return std::make_unique<WorldAssemblerNode>(c.assembler, c.mounting.toMounting());
        } else {
          static_assert(std::is_same_v<T, RotatingProfileConfig>, "a rig kind not dispatched");
          return std::make_unique<ProfileAssemblerNode>(c.geometry.toGeometry());
        }
      },
      rig->config);
  lcm::LCM lcm(common.lcm_url);
  installStopSignals();
  return runLive(lcm, {node.get()}, liveOptions(common));
}
