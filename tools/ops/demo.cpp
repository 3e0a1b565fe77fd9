#include "tools/ops/demo.hpp"

#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <thread>

#include "processes/channels.hpp"
#include "rigs/rig_file.hpp"
#include "tools/offline/replay.hpp"
#include "tools/ops/netns.hpp"
#include "tools/ops/process_group.hpp"

namespace sweepmap {

// Long because it is one script: start the processes in dependency order, wait for the
// motor's sweeps, stop them in reverse order with the pauses the last messages need, replay
// the log, and tell the user where everything is. Each step is a few lines.
int runDemo(const DemoOptions& o) {
  namespace fs = std::filesystem;
  const fs::path bin = fs::read_symlink("/proc/self/exe").parent_path();
  const fs::path out = fs::absolute(o.out);
  fs::create_directories(out / "logs");
  const std::string mode_set = "motor.mode=" + std::to_string(o.mode);
  const Rig loaded = loadRig(o.rig, {mode_set});
  const RotatingLidarConfig rig_config = requireKind<RotatingLidarConfig>(loaded, "the live demo");
  const std::string rig = fs::absolute(loaded.path).string();
  const std::string scene =
      fs::absolute(resolveConfigFile(o.scene.empty() ? defaultSceneName(loaded.kind()) : o.scene))
          .string();

  std::string why;
  if (enterPrivateNetwork(&why)) {
    std::cout << "demo: running in a private network namespace (lo only)\n";
  } else {
    std::cout << "demo: network namespaces unavailable (" << why
              << "); using LCM's default URL with ttl=0 (this host only)\n";
  }
  const std::string url = kDefaultLcmUrl;
  const std::string log = (out / "demo.lcmlog").string();
  fs::remove(log);

  ProcessGroup procs;
  const auto logFile = [&](const std::string& n) { return (out / "logs" / (n + ".txt")).string(); };
  const pid_t logger =
      procs.start("lcm-logger", {"lcm-logger", "--lcm-url=" + url, "-f", log}, logFile("logger"));
  const pid_t mapper = procs.start(
      "mapper",
      {(bin / "sweepmap-mapper").string(), "--rig", rig, "--set", mode_set, "--lcm-url", url,
       "--save", (out / "live_map.bt").string()},
      logFile("mapper"));
  const pid_t assembler = procs.start(
      "assembler",
      {(bin / "sweepmap-assembler").string(), "--rig", rig, "--set", mode_set, "--lcm-url", url},
      logFile("assembler"));
  const pid_t lidar = procs.start(
      "lidar",
      {(bin / "sweepmap-lidar").string(), "--rig", rig, "--set", mode_set, "--lcm-url", url,
       "--sim", "--scene", scene, "--seed", std::to_string(o.seed)},
      logFile("lidar"));
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // subscribers ready
  const pid_t motor = procs.start(
      "motor",
      {(bin / "sweepmap-motor").string(), "--rig", rig, "--set", mode_set, "--lcm-url", url,
       "--sim", "--sweeps", std::to_string(o.sweeps), "--seed", std::to_string(o.seed)},
      logFile("motor"));

  const double per_sweep_s = scanMode(o.mode).period_s + 15.0;
  std::cout << "demo: " << o.sweeps << " sweeps in mode " << o.mode << ", about "
            << static_cast<int>(o.sweeps * (scanMode(o.mode).period_s + 5.0))
            << " s; processes log to " << (out / "logs").string() << "\n";
  const int motor_rc = procs.wait(motor, o.sweeps * per_sweep_s + 30.0);
  if (motor_rc != 0) std::cerr << "demo: motor ended with status " << motor_rc << "\n";
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // last scans delivered
  int failures = motor_rc != 0;
  failures += procs.stop(lidar, 5.0) != 0;
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  failures += procs.stop(assembler, 10.0) != 0;
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  failures += procs.stop(mapper, 120.0) != 0;
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  failures += procs.stop(logger, 10.0) != 0;

  std::cout << "demo: replaying " << log << "\n";
  ReplayOptions ro;
  ro.log_path = log;
  ro.out_dir = out.string();
  ro.progress = true;
  const ReplayResult r = replayLog(ro, rig_config);
  if (r.log_error) {
    std::cerr << "demo: " << r.error << "\n";
    ++failures;
  }
  std::cout << "\ndemo: done (" << r.sweeps << " sweeps, " << r.points << " points)\n"
            << "  recorded log     " << log << "\n"
            << "  per-sweep clouds " << (out / "sweeps").string() << "/sweep_*.pcd, *.ply\n"
            << "  map (replayed)   " << (out / "map.bt").string() << "\n"
            << "  map (live)       " << (out / "live_map.bt").string() << "\n"
            << "  top view         " << (out / "top_view.png").string() << "\n"
            << "  summary          " << (out / "summary.json").string() << "\n";
  return failures == 0 && r.sweeps == o.sweeps ? 0 : 1;
}

}  // namespace sweepmap
