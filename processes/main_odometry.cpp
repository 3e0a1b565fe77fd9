// sweepmap-odometry: WHEEL_TICKS + IMU -> WHEEL_ODOMETRY and ODOMETRY_POSE (rig B).
#include <lcm/lcm-cpp.hpp>

#include "processes/channels.hpp"
#include "processes/live_runner.hpp"
#include "processes/odometry_node.hpp"
#include "processes/rig_b.hpp"

#include <CLI/CLI.hpp>
#include <iostream>

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{"sweepmap-odometry: wheel odometry (Miao 2022 Eq. 2-5) and its EKF fusion with "
               "the IMU gyro (bias estimated, slip gated, late messages re-ordered); publishes "
               "WHEEL_ODOMETRY and ODOMETRY_POSE after every wheel reading"};
  std::string config_path, url = kDefaultLcmUrl;
  std::vector<std::string> sets;
  app.add_option("--rig", config_path, "rig B config file (odometry.* keys)")->required()
      ->check(CLI::ExistingFile);
  app.add_option("--set", sets, "override a key: key=value (repeatable)");
  app.add_option("--lcm-url", url, "LCM provider URL")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  OdometryConfig config;
  try {
    config = loadRigB(config_path, sets).odometry;
  } catch (const std::exception& e) {
    std::cerr << "config error: " << e.what() << "\n";
    return 2;
  }
  lcm::LCM lcm(url);
  OdometryNode node(config);
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
