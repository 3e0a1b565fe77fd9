#include "tools/ops/demo.hpp"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>

#include "core/set_arguments.hpp"
#include "processes/channels.hpp"
#include "rigs/rig_file.hpp"
#include "tools/offline/runs.hpp"
#include "tools/offline/simulation.hpp"
#include "tools/ops/netns.hpp"
#include "tools/ops/process_group.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

void pause(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

// The emulated UST-10LX of `--devices emulated`: its factory port, on loopback.
constexpr const char* kDemoEmulatorAddress = "127.0.0.1:10940";

// What both kinds' demos share: the output folder, the LCM URL in a private network, the
// process group with one log file per process, and the processes' common arguments.
struct DemoRun {
  fs::path bin;
  fs::path out;
  std::string url = kDefaultLcmUrl;
  std::string log;  // the recorded LCM log
  std::string rig;  // absolute rig file
  std::vector<std::string> rig_sets;
  ProcessGroup procs;

  std::string logFile(const std::string& name) const {
    return (out / "logs" / (name + ".txt")).string();
  }
  // bin/sweepmap-<name> --rig RIG [--set k=v]... --lcm-url URL <extra>
  pid_t startProcess(const std::string& name, const std::vector<std::string>& extra) {
    std::vector<std::string> argv = {(bin / ("sweepmap-" + name)).string(), "--rig", rig};
    appendSetArguments(&argv, rig_sets);
    argv.insert(argv.end(), {"--lcm-url", url});
    argv.insert(argv.end(), extra.begin(), extra.end());
    return procs.start(name, argv, logFile(name));
  }
  // Stops the processes in order (upstream first), each with its grace time and then a
  // pause for its last messages to reach the next; returns how many did not end cleanly.
  int stopInOrder(const std::vector<std::pair<pid_t, double>>& pids_grace, int pause_ms) {
    int failures = 0;
    for (size_t i = 0; i < pids_grace.size(); ++i) {
      if (i > 0) pause(pause_ms);
      failures += stop(pids_grace[i].first, pids_grace[i].second);
    }
    return failures;
  }
  // Stops one process; 1 (after saying how it ended and where its log is) unless it exited 0.
  int stop(pid_t pid, double grace_s) {
    if (procs.stop(pid, grace_s) == 0) return 0;
    std::cerr << "demo: " << procs.name(pid) << " ended with " << procs.describeExit(pid)
              << "; see its log in " << (out / "logs").string() << "\n";
    return 1;
  }
  // Every channel into the log, through sweepmap's own validating receive path and writer
  // (`sweepmap record`), not lcm-logger: liblcm 1.3.1's receive code dies on one bad datagram.
  pid_t startLogger() {
    fs::remove(log);
    const fs::path file(log);
    return procs.start(
        "record",
        {(bin / "sweepmap").string(), "record", "--lcm-url", url, "--preset", "all", "--out",
         file.parent_path().string(), "--name", file.filename().string(), "--force"},
        logFile("record"));
  }
};

DemoRun prepare(const DemoOptions& o, const Rig& rig, const std::vector<std::string>& rig_sets) {
  DemoRun run;
  run.bin = fs::read_symlink("/proc/self/exe").parent_path();
  run.out = fs::absolute(o.out);
  fs::create_directories(run.out / "logs");
  run.log = (run.out / "demo.lcmlog").string();
  run.rig = fs::absolute(rig.path).string();
  run.rig_sets = rig_sets;
  std::string why;
  if (enterPrivateNetwork(&why)) {
    std::cout << "demo: running in a private network namespace (lo only)\n";
  } else {
    std::cout << "demo: network namespaces unavailable (" << why
              << "); using LCM's default URL with ttl=0 (this host only)\n";
  }
  return run;
}

// Replays the recorded log offline into the output folder.
ReplayRunResult replayRecorded(const DemoRun& run, const Rig& rig) {
  std::cout << "demo: replaying " << run.log << "\n";
  ReplayRunOptions ro;
  ro.log_path = run.log;
  ro.out_dir = run.out.string();
  ro.progress = true;
  const ReplayRunResult r = replayRig(rig, ro);
  if (r.log_error) std::cerr << "demo: " << r.error << "\n";
  return r;
}

// What the emulator said when it could not keep real time (its log's lines), repeated on
// stderr: the devices' CRC errors and time jumps of then are the machine's load, not a driver's.
void sayIfEmulatorStalled(const DemoRun& run) {
  std::ifstream log(run.logFile("emulator"));
  for (std::string line; std::getline(log, line);) {
    if (line.find("could not keep real time") != std::string::npos) {
      std::cerr << "demo: " << line << "\n";
    }
  }
}

int rotatingDemo(const DemoOptions& o, const Rig& rig, const std::vector<std::string>& sets,
                 const std::string& scene) {
  DemoRun run = prepare(o, rig, sets);
  const pid_t logger = run.startLogger();
  const pid_t mapper = run.startProcess("mapper", {"--save", (run.out / "live_map.bt").string()});
  const pid_t assembler = run.startProcess("assembler", {});
  pid_t emulator = -1, lidar = -1;
  if (o.devices == "emulated") {
    // The simulated world behind a UST-10LX's protocol; it follows the simulated shaft and
    // publishes the truth, as the simulated lidar process does.
    std::vector<std::string> argv = {(run.bin / "sweepmap").string(),
                                     "emulate",
                                     "ust10lx",
                                     "--listen",
                                     kDemoEmulatorAddress,
                                     "--follow-lcm",
                                     "--rig",
                                     run.rig,
                                     "--scene",
                                     scene,
                                     "--seed",
                                     std::to_string(o.seed),
                                     "--lcm-url",
                                     run.url,
                                     "--truth",
                                     (run.out / "emulator_truth.lcmlog").string()};
    appendSetArguments(&argv, run.rig_sets);
    emulator = run.procs.start("emulator", argv, run.logFile("emulator"));
    pause(300);  // listening
    lidar = run.startProcess("lidar", {"--device", std::string("scip://") + kDemoEmulatorAddress});
  } else {
    lidar =
        run.startProcess("lidar", {"--sim", "--scene", scene, "--seed", std::to_string(o.seed)});
  }
  pause(700);  // subscribers ready
  const pid_t motor = run.startProcess(
      "motor", {"--sim", "--sweeps", std::to_string(o.sweeps), "--seed", std::to_string(o.seed)});

  const double period_s = scanMode(o.mode).period_s;
  std::cout << "demo: " << o.sweeps << " sweeps in mode " << o.mode << ", about "
            << static_cast<int>(o.sweeps * (period_s + 5.0)) << " s; processes log to "
            << (run.out / "logs").string() << "\n";
  const int motor_rc = run.procs.wait(motor, o.sweeps * (period_s + 15.0) + 30.0);
  if (motor_rc != 0) std::cerr << "demo: motor ended with status " << motor_rc << "\n";
  pause(500);  // last scans delivered
  int failures = motor_rc != 0;
  failures +=
      run.stopInOrder({{lidar, 5.0}, {assembler, 10.0}, {mapper, 120.0}, {logger, 10.0}}, 400);
  if (emulator > 0) {
    failures += run.stop(emulator, 5.0);
    sayIfEmulatorStalled(run);
  }

  const ReplayRunResult r = replayRecorded(run, rig);
  failures += r.log_error || r.sweeps != o.sweeps;
  if (r.sweeps != o.sweeps)
    std::cerr << "demo: " << r.sweeps << " of " << o.sweeps << " sweeps in the recorded log\n";
  std::cout << "\ndemo: done (" << r.summary << ")\n"
            << "  recorded log     " << run.log << "\n"
            << "  per-sweep clouds " << (run.out / "sweeps").string() << "/sweep_*.pcd, *.ply\n"
            << "  map (replayed)   " << (run.out / "map.bt").string() << "\n"
            << "  map (live)       " << (run.out / "live_map.bt").string() << "\n"
            << "  top view         " << (run.out / "top_view.png").string() << "\n"
            << "  summary          " << (run.out / "summary.json").string() << "\n";
  return failures;
}

// Waits up to timeout_s for every path to exist (the emulator's pty links).
bool waitForPaths(const std::vector<std::string>& paths, double timeout_s) {
  const auto until =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(int(timeout_s * 1000));
  while (std::chrono::steady_clock::now() < until) {
    bool all = true;
    for (const auto& p : paths) all = all && fs::exists(p);
    if (all) return true;
    pause(50);
  }
  return false;
}

int64_t wallClockUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Rig B's device processes: sweepmap-lidar and sweepmap-odometry, and with emulated devices
// the emulator behind them (-1 when not started).
struct CarProcesses {
  pid_t emulator = -1, lidar = -1, odometry = -1;
};

// The simulated car in the device processes (--devices sim), starting at `start`.
CarProcesses startSimulatedCar(DemoRun& run, const std::string& scene, const std::string& seed,
                               const std::string& start) {
  const std::vector<std::string> sim = {"--sim", "--scene",           scene, "--seed",
                                        seed,    "--sim-start-utime", start};
  CarProcesses car;
  car.lidar = run.startProcess("lidar", sim);
  car.odometry = run.startProcess("odometry", sim);
  return car;
}

// The simulated car behind the X4's, the HI219's and the wheel board's serial protocols, each
// on a pseudo-terminal (a symlink to it in DIR/dev/), publishing the truth; the device
// processes open them with the real serial drivers. nullopt (said on stderr) when the
// emulator made no pseudo-terminals.
std::optional<CarProcesses> startEmulatedCar(DemoRun& run, const std::string& scene,
                                             const std::string& seed, const std::string& start) {
  fs::create_directories(run.out / "dev");
  const std::vector<std::string> links = {(run.out / "dev" / "x4").string(),
                                          (run.out / "dev" / "hi219").string(),
                                          (run.out / "dev" / "wheelboard").string()};
  for (const auto& l : links) fs::remove(l);
  std::vector<std::string> argv = {(run.bin / "sweepmap").string(), "emulate",
                                   "x4,hi219,wheel-board", "--pty"};
  for (const auto& l : links) argv.insert(argv.end(), {"--link", l});
  argv.insert(argv.end(), {"--rig", run.rig, "--scene", scene, "--seed", seed, "--start-utime",
                           start, "--publish-truth", "--lcm-url", run.url});
  appendSetArguments(&argv, run.rig_sets);
  CarProcesses car;
  car.emulator = run.procs.start("emulator", argv, run.logFile("emulator"));
  if (!waitForPaths(links, 10.0)) {
    std::cerr << "demo: the emulator made no pseudo-terminals; see " << run.logFile("emulator")
              << "\n";
    return std::nullopt;
  }
  car.lidar = run.startProcess("lidar", {"--device", "ydlidar://" + links[0]});
  car.odometry = run.startProcess("odometry", {"--imu-device", "hi219://" + links[1],
                                               "--wheels-device", "wheelboard://" + links[2]});
  return car;
}

// Waits until the wall clock passes `end_utime`; false (said on stderr) as soon as one of
// the car's processes ends before.
bool driveUntil(DemoRun& run, const CarProcesses& car, int64_t end_utime) {
  while (wallClockUtime() < end_utime) {
    pause(200);
    for (pid_t p : {car.lidar, car.odometry, car.emulator}) {
      if (p > 0 && !run.procs.running(p)) {
        std::cerr << "demo: " << run.procs.name(p) << " ended early; see its log in "
                  << (run.out / "logs").string() << "\n";
        return false;
      }
    }
  }
  return true;
}

// Rig B live: sweepmap-lidar (X4) and sweepmap-odometry (wheel board + IMU) on one simulated
// car, started at one agreed wall-clock time: in-process (--devices sim) or behind the
// devices' serial protocols on pseudo-terminals (--devices emulated).
int mobileDemo(const DemoOptions& o, const Rig& rig, const std::vector<std::string>& rig_sets,
               const std::string& scene) {
  DemoRun run = prepare(o, rig, rig_sets);
  const double duration_s = std::get<MobileLidarConfig>(rig.config).sim.duration_s;
  const pid_t logger = run.startLogger();
  const pid_t assembler = run.startProcess("assembler", {});
  const pid_t mapper = run.startProcess("mapper", {"--save", (run.out / "live_map.bt").string()});
  pause(700);  // subscribers ready
  // The car starts when every device process is up and has opened its devices.
  const int64_t start_utime = wallClockUtime() + 2'000'000;
  const std::string seed = std::to_string(o.seed), start = std::to_string(start_utime);
  const std::optional<CarProcesses> car = o.devices == "emulated"
                                              ? startEmulatedCar(run, scene, seed, start)
                                              : startSimulatedCar(run, scene, seed, start);
  if (!car) return 1;
  std::cout << "demo: rig B drives for " << duration_s << " s on " << o.devices
            << " devices; processes log to " << (run.out / "logs").string() << "\n";
  int failures =
      !driveUntil(run, *car, start_utime + static_cast<int64_t>((duration_s + 1.0) * 1e6));
  failures += run.stopInOrder(
      {{car->lidar, 5.0}, {car->odometry, 5.0}, {assembler, 10.0}, {mapper, 120.0}, {logger, 10.0}},
      300);
  if (car->emulator > 0) {
    failures += run.stop(car->emulator, 5.0);
    sayIfEmulatorStalled(run);
  }

  const ReplayRunResult r = replayRecorded(run, rig);
  failures += r.log_error || r.scans == 0;
  if (r.scans == 0) std::cerr << "demo: the recorded log holds no scan\n";
  std::cout << "\ndemo: done (" << r.summary << ")\n"
            << "  recorded log     " << run.log << "\n"
            << "  world cloud      " << (run.out / "cloud.pcd").string() << "\n"
            << "  map (replayed)   " << (run.out / "map.bt").string() << "\n"
            << "  map (live)       " << (run.out / "live_map.bt").string() << "\n"
            << "  top view         " << (run.out / "top_view.png").string() << "\n"
            << "  summary          " << (run.out / "summary.json").string() << "\n";
  return failures;
}

// Rig C live: sweepmap-profiler drives the simulated turntable and profile sensor through one
// sweep per plate pose (or one of the test piece), -assembler places the profiles by Eq. 7,
// -mapper maps them.
int profileDemo(const DemoOptions& o, const Rig& rig, const std::vector<std::string>& rig_sets) {
  DemoRun run = prepare(o, rig, rig_sets);
  const RotatingProfileConfig& config = std::get<RotatingProfileConfig>(rig.config);
  const int sweeps = config.sim.scene == "plate" ? config.sim.plate_count : 1;
  const double sweep_s =
      std::fabs(config.turntable.sweep_end_deg - config.turntable.sweep_start_deg) /
      config.turntable.speed_deg_s;
  const double run_s = sweeps * (2 * sweep_s + config.sim.pause_s);
  const pid_t logger = run.startLogger();
  const pid_t mapper = run.startProcess("mapper", {"--save", (run.out / "live_map.bt").string()});
  const pid_t assembler = run.startProcess("assembler", {});
  pause(700);  // subscribers ready
  std::ostringstream pause_s;
  pause_s << config.sim.pause_s;
  const pid_t profiler =
      run.startProcess("profiler", {"--sim", "--sweeps", std::to_string(sweeps), "--seed",
                                    std::to_string(o.seed), "--pause-s", pause_s.str()});
  std::cout << "demo: rig C, " << sweeps << " sweeps of the " << config.sim.scene << ", about "
            << static_cast<int>(run_s + 3) << " s; processes log to " << (run.out / "logs").string()
            << "\n";
  const int profiler_rc = run.procs.wait(profiler, run_s + 60.0);
  if (profiler_rc != 0) std::cerr << "demo: profiler ended with status " << profiler_rc << "\n";
  int failures = profiler_rc != 0;
  failures += run.stopInOrder({{assembler, 10.0}, {mapper, 120.0}, {logger, 10.0}}, 400);

  const ReplayRunResult r = replayRecorded(run, rig);
  failures += r.log_error || r.sweeps != sweeps;
  if (r.sweeps != sweeps)
    std::cerr << "demo: " << r.sweeps << " of " << sweeps << " sweeps in the recorded log\n";
  std::cout << "\ndemo: done (" << r.summary << ")\n"
            << "  recorded log     " << run.log << "\n"
            << "  cloud (O_r)      " << (run.out / "cloud.pcd").string() << "\n"
            << "  per-sweep clouds " << (run.out / "sweeps").string() << "/sweep_*.pcd\n"
            << "  map (replayed)   " << (run.out / "map.bt").string() << "\n"
            << "  map (live)       " << (run.out / "live_map.bt").string() << "\n"
            << "  top view         " << (run.out / "top_view.png").string() << "\n"
            << "  summary          " << (run.out / "summary.json").string() << "\n";
  return failures;
}

}  // namespace

int runDemo(const DemoOptions& o) {
  std::vector<std::string> rig_sets, scene_sets;
  splitSimOverrides(o.overrides, &rig_sets, &scene_sets);
  if (!scene_sets.empty()) {
    throw ConfigError(
        "scene.<key> overrides are for `sweepmap sim`; give the demo another --scene file");
  }
  if (o.devices != "sim" && o.devices != "emulated") {
    throw ConfigError("--devices must be sim or emulated");
  }
  Rig rig = loadRig(o.rig, rig_sets);
  if (auto* profile = std::get_if<RotatingProfileConfig>(&rig.config)) {
    if (o.devices != "sim") {
      throw ConfigError("--devices " + o.devices + ": " + rig.path +
                        " is a rotating_profile rig: only simulated devices (no protocol, "
                        "driver or emulator for its turntable and profile sensor yet)");
    }
    // Rig C's scenes are built in: --scene picks one (plate | test_piece).
    if (!o.scene.empty()) {
      if (o.scene != "plate" && o.scene != "test_piece") {
        throw ConfigError("--scene '" + o.scene +
                          "': a rotating_profile rig's scene is plate or test_piece");
      }
      profile->sim.scene = o.scene;
      rig_sets.push_back("sim.scene=" + o.scene);  // for the processes
    }
    return profileDemo(o, rig, rig_sets) == 0 ? 0 : 1;
  }
  const std::string scene =
      fs::absolute(resolveConfigFile(o.scene.empty() ? defaultSceneName(rig.kind()) : o.scene))
          .string();
  switch (rig.kind()) {
    case RigKind::kRotatingLidar: {
      if (o.mode < 1 || o.mode > 7) throw ConfigError("--mode must be 1..7");
      std::get<RotatingLidarConfig>(rig.config).motor.mode = o.mode;
      rig_sets.push_back("motor.mode=" + std::to_string(o.mode));  // for the processes
      return rotatingDemo(o, rig, rig_sets, scene) == 0 ? 0 : 1;
    }
    case RigKind::kMobileLidar:
      return mobileDemo(o, rig, rig_sets, scene) == 0 ? 0 : 1;
    case RigKind::kRotatingProfile:
      break;  // run above
  }
  return 1;
}

}  // namespace sweepmap
