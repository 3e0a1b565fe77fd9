// sweepmap-odometry: WHEEL_TICKS + IMU -> WHEEL_ODOMETRY and ODOMETRY_POSE (rig B).
#include <lcm/lcm-cpp.hpp>

#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "processes/odometry_node.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-odometry: wheel odometry (Miao 2022 Eq. 2-5) and its EKF fusion with "
      "the IMU gyro (bias estimated, slip gated, late messages re-ordered); publishes "
      "WHEEL_ODOMETRY and ODOMETRY_POSE after every wheel reading"};
  CommonOptions common;
  addCommonOptions(app, common);
  CLI11_PARSE(app, argc, argv);
  const std::optional<Rig> rig = loadRigOrReport(common);
  if (!rig) return 2;
  const auto* config = rigOfKindOrReport<MobileLidarConfig>(*rig, "sweepmap-odometry");
  if (!config) return 2;
  lcm::LCM lcm(common.lcm_url);
  OdometryNode node(config->odometry);
  installStopSignals();
  // The odometry polls no device: ticks only time its 1 Hz status, and the default 1 ms
  // tick woke the worker 1000 times a second. Its messages are small and cheap (a few us
  // each), so the worker takes them from LCM at each 10 ms tick instead of being woken for
  // each: at 400 Hz IMU the thread switches, not the EKF, were most of its CPU (sweepmap
  // bench: ~0.1 % of a core for the EKF in process).
  LiveOptions options;
  options.tick_period_ms = 10;
  options.wake_on_message = false;
  return runLive(lcm, {&node}, options);
}
