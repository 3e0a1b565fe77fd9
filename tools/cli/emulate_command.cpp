// `sweepmap emulate`: a simulated lidar behind its real protocol (tools/emulate/).
#include <algorithm>
#include <atomic>
#include <csignal>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <sstream>
#include <thread>

#include "core/command_line.hpp"
#include "core/config.hpp"
#include "core/event_log.hpp"
#include "processes/convert.hpp"
#include "processes/live_runner.hpp"
#include "tools/cli/commands.hpp"
#include "tools/emulate/devices.hpp"
#include "tools/emulate/emulator_server.hpp"
#include "tools/emulate/odometry_emulators.hpp"
#include "tools/emulate/world.hpp"

namespace sweepmap {
namespace {

constexpr const char* kTruthLidarScanChannel = "TRUTH_LIDAR_SCAN";

struct EmulateOptions {
  std::string models;  // comma-separated
  ServerOptions server;
  std::vector<std::string> links;  // one per model
  std::string fault_device;        // the model the link faults apply to ("" = the first)
  EmulatorWorldOptions world;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  EmulatedClock clock;
  LinkFaults faults;
  std::string truth;
  int64_t start_utime = 0;
  std::string imu_frames = "91";  // hi219: 91 (the 0x91 record) | old (the old item set)
};

bool isLidarModel(const std::string& m) { return m == "ust10lx" || m == "x4" || m == "rplidar"; }

std::vector<std::string> splitModels(const std::string& list) {
  std::vector<std::string> out;
  size_t at = 0;
  while (at <= list.size()) {
    size_t comma = list.find(',', at);
    if (comma == std::string::npos) comma = list.size();
    const std::string m = list.substr(at, comma - at);
    if (!isLidarModel(m) && m != "hi219" && m != "wheel-board") {
      throw ConfigError("unknown device '" + m + "' (ust10lx, x4, rplidar, hi219, wheel-board)");
    }
    for (const std::string& seen : out) {
      if (seen == m) throw ConfigError("device '" + m + "' given twice");
    }
    out.push_back(m);
    at = comma + 1;
  }
  int lidars = 0;
  for (const std::string& m : out) lidars += isLidarModel(m);
  if (lidars > 1) throw ConfigError("one lidar per emulator process");
  return out;
}

// The options' combination checked against the devices served; true when it is the one TCP
// device (ust10lx). Throws ConfigError naming the option to change.
bool checkServing(const EmulateOptions& o, const std::vector<std::string>& models) {
  // ust10lx: TCP (--listen), or a pty (--pty) as a URG-04LX's USB port.
  const bool tcp = models.size() == 1 && models[0] == "ust10lx" && !o.server.pty;
  for (const std::string& m : models) {
    if (m == "ust10lx" && models.size() > 1) {
      throw ConfigError("ust10lx is served alone (--listen, or --pty)");
    }
  }
  if (!tcp && !o.server.listen.empty()) {
    throw ConfigError(o.models + ": serial devices: use --pty, not --listen");
  }
  if (!o.links.empty() && o.links.size() != models.size()) {
    throw ConfigError("--link: give one path per device (" + std::to_string(models.size()) + ")");
  }
  const std::string faulty = o.fault_device.empty() ? models[0] : o.fault_device;
  if (std::find(models.begin(), models.end(), faulty) == models.end()) {
    throw ConfigError("--fault-device '" + faulty + "' is not served here");
  }
  return tcp;
}

// What the served devices read from the simulated world, and the truth log beside it.
struct WorldFeeds {
  std::unique_ptr<EventLogWriter> truth;
  std::atomic<int64_t> lidar_power_on{0};
  ScanSource scans;
  ImuSource imu;
  TicksSource ticks;
  DeviceClockModel device_clock;  // the odometry devices' clocks
  std::string scip_model;         // the world rig's lidar.model (ust10lx serves it)
};

// The world's sources for `models`. Truth: each scan as the world made it (true first-ray
// time, exact ranges), its device_stamp the sensor's counter at the first ray.
void connectFeeds(const EmulateOptions& o, const std::vector<std::string>& models,
                  EmulatorWorld& world, int64_t start, WorldFeeds& f) {
  if (!o.truth.empty()) f.truth = std::make_unique<EventLogWriter>(o.truth);
  f.lidar_power_on = start;
  f.scip_model = world.lidarModel();
  for (const std::string& m : models) {
    if (!isLidarModel(m)) continue;
    ScanSource inner = world.source(beamOffsetOf(emulatedModel(m)));
    f.scans = [&o, &f, inner](int64_t now_us) {
      std::vector<Scan2D> scans = inner(now_us);
      if (!f.truth) return scans;
      for (const Scan2D& s : scans) {
        Scan2D t = s;
        t.device_stamp = o.clock.counterAt(f.lidar_power_on, s.utime);
        Outbox out;
        out.publish(kTruthLidarScanChannel, s.utime, toLcm(t));
        for (const Message& msg : out.take()) f.truth->write(msg.utime, msg.channel, msg.data);
      }
      f.truth->flush();
      return scans;
    };
  }
  f.device_clock.offset_us = (static_cast<double>(o.clock.start_ms) + o.clock.offset_ms) * 1e3;
  f.device_clock.drift_ppm = o.clock.drift_ppm;
  const auto serves = [&](const char* m) {
    return std::find(models.begin(), models.end(), m) != models.end();
  };
  if (serves("hi219")) f.imu = world.imuSource();
  if (serves("wheel-board")) f.ticks = world.ticksSource();
}

// The world's LCM side (--follow-lcm, --publish-truth): its nodes run live on a thread until
// `stop`. Nothing when the world has no node.
struct LcmSide {
  std::unique_ptr<lcm::LCM> lcm;
  std::thread thread;
  std::atomic<bool> stop{false};

  void start(const EmulateOptions& o, EmulatorWorld& world) {
    const std::vector<Node*> nodes = world.nodes();
    if (nodes.empty()) return;
    lcm = std::make_unique<lcm::LCM>(o.lcm_url);
    if (!lcm->good()) {
      throw CommandError(kExitDeviceIo, "cannot open LCM at '" + o.lcm_url + "'");
    }
    publishAll(*lcm, world.startMessages(wallUtime()));
    LiveOptions lo(o.lcm_url);
    lo.should_stop = [this] { return stop.load(); };
    thread = std::thread([this, nodes, lo] { runLive(*lcm, nodes, lo); });
  }
  ~LcmSide() {
    stop = true;
    if (thread.joinable()) thread.join();
  }
};

// Lines written to it go to stdout whole, prefixed with the device's name (several device
// threads print).
struct LineOut : std::streambuf {
  std::mutex* m;
  std::string prefix, line;
  int overflow(int c) override {
    if (c == '\n') {
      std::lock_guard<std::mutex> lock(*m);
      std::cout << prefix << line << std::endl;
      line.clear();
    } else if (c != EOF) {
      line.push_back(static_cast<char>(c));
    }
    return c;
  }
};

// One server thread per device until a stop signal, --duration or a failure (which stops
// them all and is rethrown).
void serveAll(const EmulateOptions& o, const std::vector<std::string>& models, bool tcp,
              WorldFeeds& f) {
  const std::string faulty = o.fault_device.empty() ? models[0] : o.fault_device;
  std::atomic<bool> server_stop{false};
  std::thread watcher([&] {
    while (!server_stop && !stopRequested())
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    server_stop = true;
  });
  std::mutex error_mutex, info_mutex;
  std::exception_ptr error;
  std::vector<std::thread> servers;
  for (size_t i = 0; i < models.size(); ++i) {
    const std::string model = models[i];
    ServerOptions server = o.server;
    if (!tcp) server.pty = true;
    if (tcp && server.listen.empty()) server.listen = "127.0.0.1:10940";
    if (!o.links.empty()) server.pty_link = o.links[i];
    const LinkFaults faults = model == faulty ? o.faults : LinkFaults{};
    const std::function<std::unique_ptr<EmulatedLidar>(int64_t)> make =
        [&, model](int64_t now_us) -> std::unique_ptr<EmulatedLidar> {
      if (model == "hi219") {
        return std::make_unique<Hi219Device>(
            f.imu, f.device_clock, now_us,
            o.imu_frames == "old" ? Hi219Frames::kOldItems : Hi219Frames::kImusol91);
      }
      if (model == "wheel-board") {
        return std::make_unique<WheelBoardDevice>(f.ticks, f.device_clock, now_us);
      }
      f.lidar_power_on = now_us;
      return makeEmulatedLidar(emulatedModel(model), f.scans, o.clock, now_us, f.scip_model);
    };
    servers.emplace_back([&, server, faults, make, model] {
      try {
        LineOut buf;
        buf.m = &info_mutex;
        buf.prefix = models.size() > 1 ? model + ": " : "";
        std::ostream out(&buf);
        serveEmulator(make, server, faults, wallUtime, server_stop, out);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        server_stop = true;
      }
    });
  }
  for (std::thread& t : servers) t.join();
  server_stop = true;
  watcher.join();
  if (error) std::rethrow_exception(error);
}

int runEmulate(const EmulateOptions& o) {
  const std::vector<std::string> models = splitModels(o.models);
  const bool tcp = checkServing(o, models);
  EmulatorWorldOptions wo = o.world;
  if (wo.rig.empty()) wo.rig = tcp ? "rig_a" : "rig_b";
  wo.clock_drift_ppm = o.clock.drift_ppm;
  const int64_t start = o.start_utime > 0 ? o.start_utime : wallUtime();
  std::unique_ptr<EmulatorWorld> world = makeEmulatorWorld(wo, start);
  WorldFeeds feeds;
  connectFeeds(o, models, *world, start, feeds);
  installStopSignals();
  LcmSide lcm_side;
  lcm_side.start(o, *world);
  serveAll(o, models, tcp, feeds);
  return kExitOk;
}

}  // namespace

// `sweepmap emulate --help`'s description.
constexpr const char* kEmulateDescription =
    "Serve simulated devices behind their real protocols, for the real drivers: ust10lx "
    "(a Hokuyo SCIP 2.0 sensor over TCP, as the world rig's lidar.model: the UST-10LX of "
    "rig_a, or e.g. --set lidar.model=UTM-30LX; fed by a rotating_lidar world: the simulated "
    "lidar "
    "on a shaft that stands still, or follows TRUTH_SHAFT with --follow-lcm); on "
    "pseudo-terminals, fed by a mobile_lidar world (the simulated car): x4 (YDLIDAR X4), "
    "rplidar (RPLIDAR A1), hi219 (HiPNUC HI219 IMU) and wheel-board (our wheel board "
    "protocol). Prints the address or the pty path to open, and says when it stalled (the "
    "machine too busy for it to keep real time: its bytes then come in a burst and may be "
    "lost, which the host must not blame on the device). Faults: sensor clock offset, "
    "drift and start (the 24-bit wrap), corrupted bytes, a stall, a hang-up and return.";

Runner addEmulateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("emulate", kEmulateDescription);
  auto o = std::make_shared<EmulateOptions>();
  cmd->add_option("devices", o->models,
                  "ust10lx | x4 | rplidar | hi219 | wheel-board, or several serial ones "
                  "comma-separated (x4,hi219,wheel-board: rig B's three devices on one world, "
                  "each on its own pty)")
      ->required();
  cmd->add_option("--listen", o->server.listen,
                  "ust10lx: loopback HOST:PORT to serve on (default 127.0.0.1:10940)");
  cmd->add_flag("--pty", o->server.pty,
                "serial devices: serve each on a new pseudo-terminal (default); ust10lx: serve "
                "SCIP on a pty, as a URG-04LX's USB port (open it as scip:///dev/pts/N)");
  cmd->add_option("--link", o->links,
                  "serial devices: keep a symlink to each device's pty at this path (stable "
                  "across hang-ups); one per device, in order")
      ->delimiter(',');
  cmd->add_option("--fault-device", o->fault_device,
                  "the device the link faults below apply to (default: the first)");
  cmd->add_flag(
      "--publish-truth", o->world.publish_truth,
      "mobile rigs: publish the car's TRUTH_POSE, TRUTH_MOUNTING and TRUTH_MOBILE_RIG on LCM");
  cmd->add_option("--start-utime", o->start_utime,
                  "when the simulated world starts [us, wall clock]; 0 = now")
      ->capture_default_str();
  cmd->add_option("--rig", o->world.rig,
                  "rig file or name of the world (default: rig_a for "
                  "ust10lx, rig_b otherwise)");
  cmd->add_option("--scene", o->world.scene, "scene file or name (default: the rig kind's)");
  cmd->add_option("--set", o->world.overrides, "override a rig key: key=value (repeatable)");
  cmd->add_option("--seed", o->world.seed, "simulation seed")->capture_default_str();
  cmd->add_option("--imu-frames", o->imu_frames,
                  "hi219: what the IMU streams: 91 (the 0x91 record, with its time stamp) or old "
                  "(the old item set 0x90 A0 B0 C0 D0 F0 an HI219 sends by default, no time "
                  "stamp)")
      ->capture_default_str()
      ->check(CLI::IsMember({"91", "old"}));
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
  return [o]() -> int { return runEmulate(*o); };  // a ConfigError: exit status 2
}

}  // namespace sweepmap
