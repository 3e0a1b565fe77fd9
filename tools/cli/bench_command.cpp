// `sweepmap bench`: speed and memory figures of each rig kind (tools/bench/).
#include <unistd.h>

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include "core/command_line.hpp"
#include "core/progress.hpp"
#include "rigs/rig_file.hpp"
#include "tools/bench/bench_calibration.hpp"
#include "tools/bench/bench_devices.hpp"
#include "tools/bench/bench_mobile.hpp"
#include "tools/bench/bench_onboard.hpp"
#include "tools/bench/bench_profile.hpp"
#include "tools/bench/bench_rotating.hpp"
#include "tools/bench/bench_stepper.hpp"
#include "tools/cli/commands.hpp"

namespace sweepmap {

namespace {

// What `sweepmap bench` measures, for its --help.
const char* const kBenchDescription =
    "Measure speed and memory for each rig given (default: rig_a, rig_b and rig_c). "
    "rotating_lidar: simulation and offline replay speed (assembly + plate correction + "
    "OctoMap) as real-time factors for modes 1 and 7, points per second, one sweep's plate "
    "correction and peak memory. mobile_lidar: EKF updates per second, the CPU share of the "
    "sweepmap-odometry process at 100/200/400 Hz IMU (private network namespace), and "
    "`sweepmap replay` real-time factors on a circle and a lab loop. Then the real-device "
    "drivers: each protocol decoder's throughput (MB/s, scans/s, and as a multiple of the "
    "device's own data rate), the CPU share of sweepmap-lidar driving an emulated "
    "UST-10LX at 40 Hz, of sweepmap-odometry reading the emulated HI219 (400 Hz) and "
    "wheel board (100 Hz) and of sweepmap-motor sweeping the simulated stepper in mode 7, "
    "with each one's peak RSS, and the GPIO step generator's timing (emitted - planned step "
    "times, its thread's CPU share) through a mode-7 sweep on a fake chip, about 17 s; then "
    "one line per on-board process and their estimated load on a Raspberry Pi 3B, scaled by "
    "a reference workload measured in the same run (sysbench 1.0's cpu loop) against its "
    "published Pi figure (--no-devices skips all this). rotating_profile (rig C): the "
    "axis-offset calibration on the default simulated plates (calib axis-offset's default "
    "point subset), ours (Ceres) against the paper's grid search over its interval at 1 mm "
    "and at 0.1 mm (10x finer), as seconds and a ratio. Then the calibrations (--no-calib "
    "skips them): per rig, `sweepmap calib rig` on the recording `sweepmap calib plan` "
    "recommends (rig A: 10 mode-7 sweeps; rig B: the 360 s figure-eight with stops; rig C: "
    "the three plates), simulated by `sweepmap sim` with every build error at its default: "
    "the command's wall time, CPU time and peak RSS and each parameter's error against the "
    "simulator's truth; for rig B also the joint calibration on 5 seeds, and the "
    "single-parameter `calib mounting` before issue 23 (its reference solver, minutes) and "
    "today's on the 120 s circle with exact odometry, in the same run: their times and "
    "mounting errors, and the speed-up against the old one of calib rig on as much driving "
    "(the plan's drive cut to 120 s). Prints figures; run on an idle machine, compare ratios "
    "within one run";

struct BenchArgs {
  std::vector<std::string> rigs = {"rig_a", "rig_b", "rig_c"};
  std::string scene;
  std::string work = "build/bench";
  int sweeps = 2;
  double odometry_feed_s = RigBBenchOptions{}.process_feed_s;
  bool no_devices = false;
  bool only_devices = false;
  bool no_calib = false;
  bool only_calib = false;
  double lidar_process_s = DevicesBenchOptions{}.process_s;
};

void addBenchOptions(CLI::App* cmd, BenchArgs* o) {
  cmd->add_option("--rig", o->rigs, "rig files or names to bench (repeatable)")
      ->capture_default_str();
  cmd->add_option("--scene", o->scene, "scene file or name (default: each rig kind's scene)");
  cmd->add_option("--work", o->work, "scratch directory")->capture_default_str();
  cmd->add_option("--sweeps", o->sweeps, "rotating_lidar: sweeps per mode")
      ->capture_default_str()
      ->check(atLeast(1));
  cmd->add_option("--odometry-feed-s", o->odometry_feed_s,
                  "mobile_lidar: log time fed to sweepmap-odometry per IMU rate")
      ->capture_default_str()
      ->check(greaterThan(0));
  cmd->add_flag("--no-devices", o->no_devices,
                "skip the decoders, the device processes (lidar, odometry) and the step "
                "generator");
  cmd->add_flag("--only-devices", o->only_devices,
                "only the decoders, the device processes (lidar, odometry) and the step "
                "generator");
  cmd->add_flag("--no-calib", o->no_calib,
                "skip the calibrations (calib rig per rig, rig B's old calib mounting)");
  cmd->add_flag("--only-calib", o->only_calib,
                "only the calibrations (calib rig per rig, rig B's old calib mounting)");
  cmd->add_option("--lidar-process-s", o->lidar_process_s,
                  "how long the CPU share of each device process (sweepmap-motor, -lidar, "
                  "-odometry) is measured")
      ->capture_default_str()
      ->check(greaterThan(0));
}

// The folder of this executable when `sibling` (a process executable) is beside it, else "".
std::string binDirWith(const std::string& sibling) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return !ec && fs::exists(self.parent_path() / sibling) ? self.parent_path().string() : "";
}

// One rig's figures, by its kind.
void benchRig(const Rig& rig, const BenchArgs& o) {
  const std::string scene = o.scene.empty() ? defaultSceneName(rig.kind()) : o.scene;
  switch (rig.kind()) {
    case RigKind::kRotatingLidar: {
      RotatingBenchOptions b;
      b.rig = rig.path;
      b.scene = scene;
      b.work = o.work;
      b.sweeps = o.sweeps;
      benchRotating(b, std::cout);
      break;
    }
    case RigKind::kMobileLidar: {
      RigBBenchOptions b;
      b.rig = rig.path;
      b.scene = scene;
      b.work = o.work;
      b.process_feed_s = o.odometry_feed_s;
      std::error_code ec;
      b.sweepmap_exe = std::filesystem::read_symlink("/proc/self/exe", ec).string();
      b.bin_dir = binDirWith("sweepmap-odometry");
      benchRigB(b, std::cout);
      break;
    }
    case RigKind::kRotatingProfile: {
      ProfileBenchOptions b;
      b.rig = rig.path;
      benchProfile(b, std::cout);
      break;
    }
  }
}

// One rig's calibration figures: calib rig on calib plan's recording (rig B: also the old
// calib mounting, and the joint calibration on several seeds).
void benchRigCalibration(const Rig& rig, const BenchArgs& o) {
  CalibrationBenchOptions c;
  c.work = o.work;
  std::error_code ec;
  c.sweepmap_exe = std::filesystem::read_symlink("/proc/self/exe", ec).string();
  benchCalibration(c, rig, std::cout);
  if (rig.kind() == RigKind::kMobileLidar) {
    RigBBenchOptions b;
    b.rig = rig.path;
    b.work = o.work;
    benchRigBCalibrationSeeds(b, std::cout);
  }
}

// The real-device drivers, the step generator and the on-board estimate.
void benchDeviceDrivers(const std::vector<Rig>& rigs, const BenchArgs& o) {
  std::cout << "== real-device drivers\n";
  DevicesBenchOptions d;
  d.process_s = o.lidar_process_s;
  d.bin_dir = binDirWith("sweepmap-lidar");
  std::vector<ProcessLoad> loads;
  benchDevices(d, std::cout, &loads);
  StepperBenchOptions stepper;  // rig A's motor: the first rotating_lidar rig given
  for (const Rig& rig : rigs) {
    if (const auto* rotating = std::get_if<RotatingLidarConfig>(&rig.config)) {
      stepper.motor = rotating->motor;
      break;
    }
  }
  StepperBenchResult step;
  benchStepper(stepper, std::cout, &step);
  printOnboardEstimate(loads, step.thread_cpu_share, std::cout);
}

int runBench(const BenchArgs& o) {
  std::vector<Rig> rigs;
  for (const auto& r : o.rigs) rigs.push_back(loadRig(r));  // a ConfigError: exit status 2
  std::filesystem::create_directories(o.work);
  std::cout << std::fixed << std::setprecision(2);
  std::cout << "sweepmap bench (one thread; real-time factor = simulated or logged time / "
               "wall time)\n";
  // The stage on stderr, on a terminal, only when the figures go elsewhere (a file, a pipe):
  // a progress line would break the figures' lines on the same screen.
  ProgressOptions po;
  po.enabled = isatty(STDOUT_FILENO) == 0;
  Progress progress("bench", po);
  ProgressTicker ticker(progress);
  const std::vector<Rig> none;
  for (const Rig& rig : o.only_devices || o.only_calib ? none : rigs) {
    progress.stage(rig.path);
    std::cout << "== " << rig.path << " (" << rig.kindName() << ")\n";
    benchRig(rig, o);
  }
  for (const Rig& rig : o.only_devices || o.no_calib ? none : rigs) {
    progress.stage("calibration of " + rig.path);
    std::cout << "== calibration: " << rig.path << " (" << rig.kindName() << ")\n";
    benchRigCalibration(rig, o);
  }
  if (!o.no_devices && !o.only_calib) {
    progress.stage("real-device drivers");
    benchDeviceDrivers(rigs, o);
  }
  return kExitOk;
}

}  // namespace

Runner addBenchCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("bench", kBenchDescription);
  auto o = std::make_shared<BenchArgs>();
  addBenchOptions(cmd, o.get());
  return [o]() -> int { return runBench(*o); };
}

}  // namespace sweepmap
