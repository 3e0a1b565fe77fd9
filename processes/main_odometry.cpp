// sweepmap-odometry (rig B): opens the IMU and the wheel board (imu.device, wheels.device),
// publishes their raw IMU and WHEEL_TICKS, then WHEEL_ODOMETRY and ODOMETRY_POSE; sends
// WHEEL_CMD to the board. --from-lcm: takes IMU and WHEEL_TICKS from LCM instead.
#include <lcm/lcm-cpp.hpp>
#include <memory>

#include "core/device_uri.hpp"
#include "drivers/odometry_drivers.hpp"
#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "processes/odometry_node.hpp"
#include "processes/sim_car.hpp"
#include "processes/sim_setup.hpp"
#include "sim/car_devices.hpp"

namespace sweepmap {
namespace {

struct OdometryArgs {
  CommonOptions common;
  bool from_lcm = false, sim = false;
  std::string imu_uri, wheels_uri, scene_path;
  uint64_t seed = 1;
  int64_t sim_start_utime = 0;
};

void addOdometryOptions(CLI::App& app, OdometryArgs& a) {
  addCommonOptions(app, a.common, {RigKind::kMobileLidar});
  app.add_flag("--from-lcm", a.from_lcm,
               "open no device: take IMU and WHEEL_TICKS from LCM (a log replay, or drivers on "
               "another host)");
  app.add_option("--imu-device", a.imu_uri,
                 "the IMU, overriding imu.device: sim | hi219:///dev/PORT[?baud=N]");
  app.add_option(
      "--wheels-device", a.wheels_uri,
      "the wheel board, overriding wheels.device: sim | wheelboard:///dev/PORT[?baud=N]");
  app.add_flag("--sim", a.sim, "same as --imu-device sim --wheels-device sim");
  app.add_option("--scene", a.scene_path,
                 "scene file or name of the simulated car (default: the rig kind's scene)");
  app.add_option("--seed", a.seed, "simulation seed (the same in sweepmap-lidar --sim)")
      ->capture_default_str();
  app.add_option("--sim-start-utime", a.sim_start_utime,
                 "when the simulated car starts [us, wall clock]; 0 = now. Give sweepmap-lidar "
                 "--sim the same value so that both simulate one car");
}

// The simulated car both simulated devices share, and its truth publisher's inputs.
struct SimulatedCar {
  MobileLidarConfig rig;
  SceneConfig scene_config;
  std::unique_ptr<Scene> scene;
  std::unique_ptr<SimMobile> car;
};

// Throws ConfigError (a bad scene or sim.* key).
SimulatedCar makeSimulatedCar(const Rig& rig, const MobileLidarConfig& config,
                              const OdometryArgs& a) {
  SimulatedCar s;
  s.rig = config;
  prepareSimMobileConfig(rig.path, &s.rig);
  s.scene_config = loadScene(
      resolveSceneFile(a.scene_path.empty() ? defaultSceneName(rig.kind()) : a.scene_path));
  s.scene = std::make_unique<Scene>(s.scene_config, PlateConfig{});
  s.car =
      makeSimCar(s.rig, *s.scene, a.seed, a.sim_start_utime > 0 ? a.sim_start_utime : wallUtime());
  return s;
}

// The IMU and wheel board: simulated on `car`, or the real drivers (started).
struct OdometryDevices {
  std::unique_ptr<ImuDevice> imu;
  std::unique_ptr<WheelDevice> wheels;
  std::vector<const StreamDevice*> drivers;  // their worker threads must not get stuck
};

OdometryDevices openDevices(const DeviceUri& imu_dev, const DeviceUri& wheels_dev, SimMobile* car) {
  OdometryDriverOptions driver_options;
  OdometryDevices d;
  if (imu_dev.protocol == DeviceProtocol::kSim) {
    d.imu = std::make_unique<SimImu>(car);
  } else {
    auto driver = std::make_unique<Hi219Driver>(imu_dev, driver_options, wallUtime);
    driver->start();
    d.drivers.push_back(driver.get());
    d.imu = std::move(driver);
  }
  if (wheels_dev.protocol == DeviceProtocol::kSim) {
    d.wheels = std::make_unique<SimWheels>(car);
  } else {
    auto driver = std::make_unique<WheelBoardDriver>(wheels_dev, driver_options, wallUtime);
    driver->start();
    d.drivers.push_back(driver.get());
    d.wheels = std::move(driver);
  }
  return d;
}

// The devices the rig file (or the command line) names, the node over them, live.
int runWithDevices(lcm::LCM& lcm, const Rig& rig, const MobileLidarConfig& config,
                   const OdometryArgs& a, LiveOptions options) {
  DeviceUri imu_dev, wheels_dev;
  try {
    imu_dev = parseDeviceUriFor(a.imu_uri.empty() ? config.imu_device : a.imu_uri,
                                {DeviceProtocol::kHi219});
    wheels_dev = parseDeviceUriFor(a.wheels_uri.empty() ? config.wheels_device : a.wheels_uri,
                                   {DeviceProtocol::kWheelBoard});
  } catch (const std::invalid_argument& e) {
    std::cerr << "sweepmap-odometry: " << e.what() << "\n";
    return kExitUsage;
  }
  SimulatedCar sim;
  if (imu_dev.protocol == DeviceProtocol::kSim || wheels_dev.protocol == DeviceProtocol::kSim) {
    try {
      sim = makeSimulatedCar(rig, config, a);
    } catch (const std::exception& e) {
      std::cerr << "config error: " << e.what() << "\n";
      return kExitUsage;
    }
  }
  const OdometryDevices devices = openDevices(imu_dev, wheels_dev, sim.car.get());
  OdometryNode node(config.odometry, devices.imu.get(), devices.wheels.get());
  std::vector<Node*> nodes = {&node};
  std::unique_ptr<SimCarTruthNode> truth;
  if (sim.car) {
    truth = std::make_unique<SimCarTruthNode>(sim.rig, sim.scene_config, sim.car.get());
    nodes.push_back(truth.get());
  }
  options.healthy = [&devices] {
    for (const StreamDevice* d : devices.drivers) {
      if (d->workerStalled(kDeviceWorkerStallMs)) return false;
    }
    return true;
  };
  return runLive(lcm, nodes, options);
}

}  // namespace
}  // namespace sweepmap

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-odometry: opens the rig's IMU (imu.device) and wheel board (wheels.device), "
      "publishes their samples raw on IMU and WHEEL_TICKS, then wheel odometry (Miao 2022 Eq. "
      "2-5) on WHEEL_ODOMETRY and its EKF fusion with the IMU gyro (bias estimated, slip gated, "
      "late messages re-ordered) on ODOMETRY_POSE after every wheel reading; forwards WHEEL_CMD "
      "to the wheel board. Driver counters and an IMU outage (EKF on wheels alone) show in "
      "STATUS_ODOMETRY"};
  OdometryArgs args;
  addOdometryOptions(app, args);
  if (const auto code = parseCommandLine(app, argc, argv)) return *code;
  const std::optional<Rig> rig = loadRigOrReport(args.common);
  if (!rig) return kExitUsage;
  const auto* config = rigOfKindOrReport<MobileLidarConfig>(*rig, "sweepmap-odometry");
  if (!config) return kExitUsage;
  if (args.sim) args.imu_uri = args.wheels_uri = "sim";
  lcm::LCM lcm(args.common.lcm_url);
  if (!lcm.good()) {
    std::cerr << "sweepmap-odometry: cannot open LCM at '" << args.common.lcm_url << "'\n";
    return kExitDeviceIo;
  }
  installStopSignals();
  // The odometry polls its devices (or takes its messages from LCM) every 10 ms: its
  // messages are small and cheap (a few us each), and at 400 Hz IMU thread switches per
  // message, not the EKF, were most of its CPU (sweepmap bench).
  LiveOptions options = liveOptions(args.common);
  options.tick_period_ms = 10;
  options.wake_on_message = false;
  if (args.from_lcm) {
    OdometryNode node(config->odometry);
    return runLive(lcm, {&node}, options);
  }
  return runWithDevices(lcm, *rig, *config, args, options);
}
