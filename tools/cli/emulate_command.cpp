// `sweepmap emulate`: a simulated lidar behind its real protocol (tools/emulate/).
#include <atomic>
#include <csignal>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "core/config.hpp"
#include "core/event_log.hpp"
#include "processes/convert.hpp"
#include "processes/live_runner.hpp"
#include "tools/cli/commands.hpp"
#include "tools/emulate/devices.hpp"
#include "tools/emulate/emulator_server.hpp"
#include "tools/emulate/world.hpp"

namespace sweepmap {
namespace {

constexpr const char* kTruthLidarScanChannel = "TRUTH_LIDAR_SCAN";

struct EmulateOptions {
  std::string model;
  ServerOptions server;
  EmulatorWorldOptions world;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  EmulatedClock clock;
  LinkFaults faults;
  std::string truth;
};

int runEmulate(const EmulateOptions& o) {
  const EmulatedModel model = emulatedModel(o.model);
  const bool serial = model != EmulatedModel::kUst10lx;
  ServerOptions server = o.server;
  if (serial && !server.listen.empty()) {
    throw ConfigError(o.model + " is a serial device: use --pty, not --listen");
  }
  if (!serial && server.pty) throw ConfigError("ust10lx speaks TCP: use --listen, not --pty");
  if (serial) server.pty = true;
  if (!serial && server.listen.empty()) server.listen = "127.0.0.1:10940";
  EmulatorWorldOptions wo = o.world;
  if (wo.rig.empty()) wo.rig = serial ? "rig_b" : "rig_a";
  wo.clock_drift_ppm = o.clock.drift_ppm;
  const int64_t start = wallUtime();
  std::unique_ptr<EmulatorWorld> world = makeEmulatorWorld(wo, start);

  // Truth: each scan as the world made it (true first-ray time, exact ranges), its
  // device_stamp the sensor's counter at the first ray.
  std::unique_ptr<EventLogWriter> truth;
  if (!o.truth.empty()) truth = std::make_unique<EventLogWriter>(o.truth);
  int64_t power_on = start;
  ScanSource inner = world->source();
  ScanSource source = [&](int64_t now_us) {
    std::vector<Scan2D> scans = inner(now_us);
    if (truth) {
      for (const Scan2D& s : scans) {
        Scan2D t = s;
        t.device_stamp = o.clock.counterAt(power_on, s.utime);
        Outbox out;
        out.publish(kTruthLidarScanChannel, s.utime, toLcm(t));
        for (const Message& m : out.take()) truth->write(m.utime, m.channel, m.data);
      }
      truth->flush();
    }
    return scans;
  };

  std::unique_ptr<lcm::LCM> lcm;
  std::thread lcm_thread;
  std::atomic<bool> stop{false};
  installStopSignals();
  const std::vector<Node*> nodes = world->nodes();
  if (!nodes.empty()) {
    lcm = std::make_unique<lcm::LCM>(o.lcm_url);
    if (!lcm->good()) throw ConfigError("cannot open LCM at '" + o.lcm_url + "'");
    publishAll(*lcm, world->startMessages(wallUtime()));
    LiveOptions lo;
    lo.should_stop = [&stop] { return stop.load(); };
    lcm_thread = std::thread([&lcm, nodes, lo] { runLive(*lcm, nodes, lo); });
  }
  std::atomic<bool> server_stop{false};
  std::thread watcher([&] {
    while (!server_stop && !stopRequested())
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    server_stop = true;
  });
  try {
    serveEmulator(
        [&](int64_t now_us) {
          power_on = now_us;
          return makeEmulatedLidar(model, source, o.clock, now_us);
        },
        server, o.faults, wallUtime, server_stop, std::cout);
  } catch (...) {
    server_stop = true;
    stop = true;
    watcher.join();
    if (lcm_thread.joinable()) lcm_thread.join();
    throw;
  }
  server_stop = true;
  stop = true;
  watcher.join();
  if (lcm_thread.joinable()) lcm_thread.join();
  return 0;
}

}  // namespace

Runner addEmulateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "emulate",
      "Serve a simulated lidar behind its real protocol, for the real drivers: ust10lx (Hokuyo "
      "UST-10LX, SCIP 2.0 over TCP, fed by a rotating_lidar world: the simulated lidar on a "
      "shaft that stands still, or follows TRUTH_SHAFT with --follow-lcm), x4 (YDLIDAR X4) and "
      "rplidar (RPLIDAR A1) on a pseudo-terminal (fed by a mobile_lidar world: the simulated "
      "car's lidar). Prints the address or the pty path to open. Faults: sensor clock offset, "
      "drift and start (the 24-bit wrap), corrupted bytes, a stall, a hang-up and return.");
  auto o = std::make_shared<EmulateOptions>();
  cmd->add_option("model", o->model, "ust10lx | x4 | rplidar")
      ->required()
      ->check(CLI::IsMember({"ust10lx", "x4", "rplidar"}));
  cmd->add_option("--listen", o->server.listen,
                  "ust10lx: loopback HOST:PORT to serve on (default 127.0.0.1:10940)");
  cmd->add_flag("--pty", o->server.pty, "x4, rplidar: serve on a new pseudo-terminal (default)");
  cmd->add_option("--link", o->server.pty_link,
                  "x4, rplidar: keep a symlink to the pty at this path (stable across hang-ups)");
  cmd->add_option("--rig", o->world.rig,
                  "rig file or name of the world (default: rig_a for "
                  "ust10lx, rig_b otherwise)");
  cmd->add_option("--scene", o->world.scene, "scene file or name (default: the rig kind's)");
  cmd->add_option("--set", o->world.overrides, "override a rig key: key=value (repeatable)");
  cmd->add_option("--seed", o->world.seed, "simulation seed")->capture_default_str();
  cmd->add_flag("--follow-lcm", o->world.follow_lcm,
                "ust10lx: follow TRUTH_SHAFT from a simulated stepper, publish TRUTH_RIG and "
                "TRUTH_SWEEP");
  cmd->add_option("--lcm-url", o->lcm_url, "LCM URL for --follow-lcm")->capture_default_str();
  cmd->add_option("--clock-start-ms", o->clock.start_ms,
                  "sensor counter at power-up [ms] (16777215 - 5000: the 24-bit wrap after 5 s)")
      ->capture_default_str();
  cmd->add_option("--clock-offset-ms", o->clock.offset_ms, "sensor clock offset [ms]")
      ->capture_default_str();
  cmd->add_option("--clock-drift-ppm", o->clock.drift_ppm,
                  "sensor clock rate error [ppm]; the scan rate follows it")
      ->capture_default_str();
  cmd->add_option("--corrupt-rate", o->faults.corrupt_rate,
                  "probability per sent byte of a flipped bit")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--stall-at", o->faults.stall_at_s, "stall after this many seconds (< 0: never)")
      ->capture_default_str();
  cmd->add_option("--stall-s", o->faults.stall_s, "stall length [s] (the bytes are lost)")
      ->capture_default_str();
  cmd->add_option("--hangup-at", o->faults.hangup_at_s,
                  "drop the connection / remove the pty after this many seconds (< 0: never)")
      ->capture_default_str();
  cmd->add_option("--down-s", o->faults.down_s, "then come back, powered up afresh, after [s]")
      ->capture_default_str();
  cmd->add_option("--fault-seed", o->faults.seed, "seed of the corrupted bytes")
      ->capture_default_str();
  cmd->add_option("--duration", o->server.duration_s, "stop after [s] (0: at SIGINT/SIGTERM)")
      ->capture_default_str();
  cmd->add_option("--truth", o->truth,
                  "LCM log of the world's scans as simulated (TRUTH_LIDAR_SCAN: true first-ray "
                  "time, exact ranges, device_stamp = the sensor counter at the first ray)");
  return [o]() {
    try {
      return runEmulate(*o);
    } catch (const ConfigError& e) {
      std::cerr << "config error: " << e.what() << "\n";
      return 2;
    }
  };
}

}  // namespace sweepmap
