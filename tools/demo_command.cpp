#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <thread>

#include "core/rig_config.hpp"
#include "processes/channels.hpp"
#include "tools/commands.hpp"
#include "tools/netns.hpp"
#include "tools/process_group.hpp"
#include "tools/replay.hpp"

namespace sweepmap {

std::string lcmtypesJar(const std::string& argv0);

Runner addDemoCommand(CLI::App& app, const std::string& argv0) {
  auto* cmd = app.add_subcommand(
      "demo",
      "The main job: start sweepmap-motor, -lidar (simulated devices), -assembler, -mapper and "
      "lcm-logger as separate processes in a private network namespace, make a few 3D sweeps "
      "of the default room, stop everything cleanly, replay the recorded log, and leave the "
      "log, per-sweep clouds, maps and a PNG top view in the output directory");
  struct Opts {
    std::string rig = "config/rig_a.yaml";
    std::string scene = "config/scene_conference_room.yaml";
    std::string out = "out";
    int mode = 7;
    int sweeps = 3;
    uint64_t seed = 1;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("--rig", o->rig, "rig config")->capture_default_str()->check(CLI::ExistingFile);
  cmd->add_option("--scene", o->scene, "scene")->capture_default_str()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "output directory")->capture_default_str();
  cmd->add_option("--mode", o->mode, "scan mode 1..7")->capture_default_str()->check(CLI::Range(1, 7));
  cmd->add_option("--sweeps", o->sweeps, "number of sweeps")->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o->seed, "simulation seed")->capture_default_str();
  return [o, argv0]() {
    namespace fs = std::filesystem;
    const fs::path bin = fs::read_symlink("/proc/self/exe").parent_path();
    const fs::path out = fs::absolute(o->out);
    fs::create_directories(out / "logs");
    const std::string rig = fs::absolute(o->rig).string();
    const std::string scene = fs::absolute(o->scene).string();
    const std::string mode_set = "motor.mode=" + std::to_string(o->mode);
    RigConfig rig_config = loadRig(rig, {mode_set});

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
         "--sim", "--scene", scene, "--seed", std::to_string(o->seed)},
        logFile("lidar"));
    std::this_thread::sleep_for(std::chrono::milliseconds(700));  // subscribers ready
    const pid_t motor = procs.start(
        "motor",
        {(bin / "sweepmap-motor").string(), "--rig", rig, "--set", mode_set, "--lcm-url", url,
         "--sim", "--sweeps", std::to_string(o->sweeps), "--seed", std::to_string(o->seed)},
        logFile("motor"));

    const double per_sweep_s = scanMode(o->mode).period_s + 15.0;
    std::cout << "demo: " << o->sweeps << " sweeps in mode " << o->mode << ", about "
              << static_cast<int>(o->sweeps * (scanMode(o->mode).period_s + 5.0))
              << " s; processes log to " << (out / "logs").string() << "\n";
    const int motor_rc = procs.wait(motor, o->sweeps * per_sweep_s + 30.0);
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
    return failures == 0 && r.sweeps == o->sweeps ? 0 : 1;
  };
}

}  // namespace sweepmap
