// sweepmap-odometry (rig B): opens the IMU and the wheel board (imu.device, wheels.device),
// publishes their raw IMU and WHEEL_TICKS, then WHEEL_ODOMETRY and ODOMETRY_POSE; sends
// WHEEL_CMD to the board. --from-lcm: takes IMU and WHEEL_TICKS from LCM instead.
#include <lcm/lcm-cpp.hpp>
#include <memory>

#include "core/device_uri.hpp"
#include "drivers/odometry_drivers.hpp"
#include "sim/car_devices.hpp"
#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "processes/odometry_node.hpp"
#include "processes/sim_car.hpp"
#include "processes/sim_setup.hpp"

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-odometry: opens the rig's IMU (imu.device) and wheel board (wheels.device), "
      "publishes their samples raw on IMU and WHEEL_TICKS, then wheel odometry (Miao 2022 Eq. "
      "2-5) on WHEEL_ODOMETRY and its EKF fusion with the IMU gyro (bias estimated, slip gated, "
      "late messages re-ordered) on ODOMETRY_POSE after every wheel reading; forwards WHEEL_CMD "
      "to the wheel board. Driver counters and an IMU outage (EKF on wheels alone) show in "
      "STATUS_ODOMETRY"};
  CommonOptions common;
  addCommonOptions(app, common);
  bool from_lcm = false, sim = false;
  std::string imu_uri, wheels_uri, scene_path;
  uint64_t seed = 1;
  int64_t sim_start_utime = 0;
  app.add_flag("--from-lcm", from_lcm,
               "open no device: take IMU and WHEEL_TICKS from LCM (a log replay, or drivers on "
               "another host)");
  app.add_option("--imu-device", imu_uri,
                 "the IMU, overriding imu.device: sim | hi219:///dev/PORT[?baud=N]");
  app.add_option(
      "--wheels-device", wheels_uri,
      "the wheel board, overriding wheels.device: sim | wheelboard:///dev/PORT[?baud=N]");
  app.add_flag("--sim", sim, "same as --imu-device sim --wheels-device sim");
  app.add_option("--scene", scene_path,
                 "scene file or name of the simulated car (default: the rig kind's scene)");
  app.add_option("--seed", seed, "simulation seed (the same in sweepmap-lidar --sim)")
      ->capture_default_str();
  app.add_option("--sim-start-utime", sim_start_utime,
                 "when the simulated car starts [us, wall clock]; 0 = now. Give sweepmap-lidar "
                 "--sim the same value so that both simulate one car");
  CLI11_PARSE(app, argc, argv);
  const std::optional<Rig> rig = loadRigOrReport(common);
  if (!rig) return 2;
  const auto* config = rigOfKindOrReport<MobileLidarConfig>(*rig, "sweepmap-odometry");
  if (!config) return 2;
  if (sim) imu_uri = wheels_uri = "sim";
  lcm::LCM lcm(common.lcm_url);
  if (!lcm.good()) {
    std::cerr << "sweepmap-odometry: cannot open LCM at '" << common.lcm_url << "'\n";
    return 1;
  }
  installStopSignals();
  // The odometry polls its devices (or takes its messages from LCM) every 10 ms: its
  // messages are small and cheap (a few us each), and at 400 Hz IMU thread switches per
  // message, not the EKF, were most of its CPU (sweepmap bench).
  LiveOptions options = liveOptions(common);
  options.tick_period_ms = 10;
  options.wake_on_message = false;
  if (from_lcm) {
    OdometryNode node(config->odometry);
    return runLive(lcm, {&node}, options);
  }

  DeviceUri imu_dev, wheels_dev;
  try {
    imu_dev =
        parseDeviceUriFor(imu_uri.empty() ? config->imu_device : imu_uri, {DeviceProtocol::kHi219});
    wheels_dev = parseDeviceUriFor(wheels_uri.empty() ? config->wheels_device : wheels_uri,
                                   {DeviceProtocol::kWheelBoard});
  } catch (const std::invalid_argument& e) {
    std::cerr << "sweepmap-odometry: " << e.what() << "\n";
    return 2;
  }
  // The simulated car, when either device is simulated.
  std::unique_ptr<SimMobile> car;
  std::unique_ptr<Scene> scene;
  SceneConfig scene_config;
  MobileLidarConfig rig_config = *config;
  if (imu_dev.protocol == DeviceProtocol::kSim || wheels_dev.protocol == DeviceProtocol::kSim) {
    try {
      prepareSimMobileConfig(rig->path, &rig_config);
      scene_config = loadScene(
          resolveConfigFile(scene_path.empty() ? defaultSceneName(rig->kind()) : scene_path));
      scene = std::make_unique<Scene>(scene_config, PlateConfig{});
      car =
          makeSimCar(rig_config, *scene, seed, sim_start_utime > 0 ? sim_start_utime : wallUtime());
    } catch (const std::exception& e) {
      std::cerr << "config error: " << e.what() << "\n";
      return 2;
    }
  }
  OdometryDriverOptions driver_options;
  std::unique_ptr<ImuDevice> imu;
  std::unique_ptr<WheelDevice> wheels;
  std::vector<const StreamDevice*> drivers;  // their worker threads must not get stuck
  if (imu_dev.protocol == DeviceProtocol::kSim) {
    imu = std::make_unique<SimImu>(car.get());
  } else {
    auto d = std::make_unique<Hi219Driver>(imu_dev, driver_options, wallUtime);
    d->start();
    drivers.push_back(d.get());
    imu = std::move(d);
  }
  if (wheels_dev.protocol == DeviceProtocol::kSim) {
    wheels = std::make_unique<SimWheels>(car.get());
  } else {
    auto d = std::make_unique<WheelBoardDriver>(wheels_dev, driver_options, wallUtime);
    d->start();
    drivers.push_back(d.get());
    wheels = std::move(d);
  }
  OdometryNode node(config->odometry, imu.get(), wheels.get());
  std::vector<Node*> nodes = {&node};
  std::unique_ptr<SimCarTruthNode> truth;
  if (car) {
    truth = std::make_unique<SimCarTruthNode>(rig_config, scene_config, car.get());
    nodes.push_back(truth.get());
  }
  options.healthy = [&drivers] {
    for (const StreamDevice* d : drivers) {
      if (d->workerStalled(kDeviceWorkerStallMs)) return false;
    }
    return true;
  };
  return runLive(lcm, nodes, options);
}
