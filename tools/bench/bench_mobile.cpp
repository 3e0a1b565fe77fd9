#include "tools/bench/bench_mobile.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <vector>

#include "core/event_log.hpp"
#include "core/set_arguments.hpp"
#include "processes/channels.hpp"
#include "processes/odometry_node.hpp"
#include "tools/bench/proc_stats.hpp"
#include "tools/offline/calibrate_rig.hpp"
#include "tools/offline/mobile_log.hpp"
#include "tools/offline/mobile_rig_calibration.hpp"
#include "tools/offline/replay_mobile.hpp"
#include "tools/offline/runs.hpp"
#include "tools/offline/sim_mobile.hpp"
#include "tools/ops/netns.hpp"
#include "tools/ops/process_group.hpp"

namespace sweepmap {
namespace {

using Clock = BenchClock;

struct SimulatedLog {
  MobileLidarConfig rig;
  SimMobileResult result;
  std::vector<Message> odometry_input;  // WHEEL_TICKS and IMU, in log order
};

// Simulates rig B with `overrides`; writes the whole log to `path` (if not empty), or
// only the odometry's input channels when `odometry_only`.
SimulatedLog simulate(const RigBBenchOptions& o, const std::vector<std::string>& overrides,
                      const std::string& path, bool odometry_only) {
  SimMobileOptions so;
  const SimSetup setup = loadSimSetup(o.rig, o.scene, overrides);
  so.rig = requireKind<MobileLidarConfig>(setup.rig, "the rig-B bench");
  so.scene = setup.scene;
  SimulatedLog log;
  log.rig = so.rig;
  std::unique_ptr<EventLogWriter> writer;
  if (!path.empty()) writer = std::make_unique<EventLogWriter>(path);
  log.result = simulateMobile(so, [&](const Message& m) {
    const bool odometry_input = m.channel == channels::kWheelTicks || m.channel == channels::kImu;
    if (odometry_input) log.odometry_input.push_back(m);
    if (writer && (odometry_input || !odometry_only)) writer->write(m.utime, m.channel, m.data);
  });
  if (writer) writer->close();
  return log;
}

std::string rateOverride(int imu_hz) { return "sim.imu_rate_hz=" + std::to_string(imu_hz); }

// OdometryNode (decode, wheel odometry, EKF, encode of both poses) over the simulated
// stream, repeated until at least `min_s` of wall time has passed.
void benchEkfInProcess(const RigBBenchOptions& o, std::ostream& out) {
  out << "EKF in process (OdometryNode: decode, wheel odometry, EKF, encoded poses; 50 Hz "
         "wheels):\n";
  for (int imu_hz : {100, 200, 400}) {
    const SimulatedLog log = simulate(o, {rateOverride(imu_hz), "sim.duration_s=60"}, "", false);
    int64_t messages = 0, updates = 0;
    int reps = 0;
    const auto t0 = Clock::now();
    do {
      OdometryNode node(log.rig.odometry);
      Outbox outbox;
      for (const Message& m : log.odometry_input) {
        node.receive(m, outbox);
        outbox.take();
      }
      const auto& c = node.ekf().counters();
      updates += c.wheels + c.gyro + c.yaw + c.gated_wheels + c.gated_gyro + c.gated_yaw;
      messages += static_cast<int64_t>(log.odometry_input.size());
      ++reps;
    } while (secondsSince(t0) < 1.0);
    const double wall_s = secondsSince(t0);
    const double per_log_s = wall_s / reps;
    out << "  IMU " << std::setw(3) << imu_hz << " Hz: " << std::setprecision(0) << updates / wall_s
        << " EKF updates/s, " << messages / wall_s << " messages/s, " << std::setprecision(2)
        << wall_s / messages * 1e6 << " us/message; " << log.result.duration_s
        << " s of input take " << per_log_s * 1e3 << " ms = " << std::setprecision(3)
        << per_log_s / log.result.duration_s * 100.0 << " % of one core at real time\n"
        << std::setprecision(2);
  }
}

// The real sweepmap-odometry process fed by lcm-logplayer at real-time pace, in a private
// network namespace. Its CPU share = (utime + stime) / wall time while it is fed.
void benchOdometryProcess(const RigBBenchOptions& o, std::ostream& out) {
  namespace fs = std::filesystem;
  out << "sweepmap-odometry process (lcm-logplayer at real-time pace, private network "
         "namespace; share of one core = CPU s / wall s):\n";
  std::string why;
  if (o.bin_dir.empty()) {
    out << "  skipped: no sweepmap-odometry executable\n";
    return;
  }
  if (!enterPrivateNetwork(&why)) {
    out << "  skipped: no private network namespace (" << why << ")\n";
    return;
  }
  const std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152";
  const std::string exe = (fs::path(o.bin_dir) / "sweepmap-odometry").string();
  for (int imu_hz : {100, 200, 400}) {
    const std::string log_path =
        o.work + "/odometry_input_imu" + std::to_string(imu_hz) + ".lcmlog";
    const SimulatedLog log =
        simulate(o, {rateOverride(imu_hz), "sim.duration_s=" + std::to_string(o.process_feed_s)},
                 log_path, true);
    ProcessGroup procs;
    const std::string odo_log = o.work + "/odometry_imu" + std::to_string(imu_hz) + ".txt";
    const pid_t odometry =
        procs.start("odometry", {exe, "--rig", o.rig, "--from-lcm", "--lcm-url", url}, odo_log);
    std::this_thread::sleep_for(std::chrono::milliseconds(800));  // start-up (config, LCM)
    // Baseline: the same process idle (status at 1 Hz, waiting on its socket).
    const double idle_cpu0 = processCpuSeconds(odometry);
    auto t0 = Clock::now();
    std::this_thread::sleep_for(std::chrono::seconds(3));
    const double idle_share = (processCpuSeconds(odometry) - idle_cpu0) / secondsSince(t0);

    const double children_cpu0 = cpuSeconds(RUSAGE_CHILDREN);
    const double cpu0 = processCpuSeconds(odometry);
    const int64_t switches0 = contextSwitches(odometry);
    t0 = Clock::now();
    const pid_t player = procs.start("logplayer", {"lcm-logplayer", "--lcm-url=" + url, log_path},
                                     o.work + "/logplayer.txt");
    const int rc = procs.wait(player, o.process_feed_s * 3 + 10);
    const double fed_s = secondsSince(t0);
    const double share = (processCpuSeconds(odometry) - cpu0) / fed_s;
    const double switches_per_s = (contextSwitches(odometry) - switches0) / fed_s;
    const double player_share = (cpuSeconds(RUSAGE_CHILDREN) - children_cpu0) / fed_s;
    procs.stop(odometry, 5.0);
    if (rc != 0 || cpu0 < 0) {
      out << "  IMU " << imu_hz << " Hz: lcm-logplayer or sweepmap-odometry failed (see " << o.work
          << ")\n";
      continue;
    }
    out << "  IMU " << std::setw(3) << imu_hz << " Hz + 50 Hz wheels: " << std::setprecision(0)
        << log.odometry_input.size() / fed_s << " messages/s for " << std::setprecision(1) << fed_s
        << " s: sweepmap-odometry " << std::setprecision(2) << share * 100.0 << " % of one core, "
        << std::setprecision(0) << switches_per_s
        << " thread switches/s (idle: " << std::setprecision(2) << idle_share * 100.0
        << " %; lcm-logplayer itself: " << player_share * 100.0 << " %)\n";
  }
  out << "  (/proc counts CPU in clock ticks of " << 1000 / sysconf(_SC_CLK_TCK) << " ms: +-"
      << std::setprecision(2) << 100.0 / sysconf(_SC_CLK_TCK) / o.process_feed_s
      << " % over one run)\n";
}

void benchReplay(const RigBBenchOptions& o, std::ostream& out) {
  out << "sweepmap replay --no-plots (odometry + world assembler + mapper + outputs; the "
         "command's wall time, start-up included, its CPU time (less "
         "sensitive to a busy machine) and its peak RSS):\n";
  struct Case {
    const char* name;
    std::vector<std::string> overrides;
  };
  // The same circle with every scan inserted on its own: the batching's share, same run.
  const std::string circle = "sim.duration_s=" + std::to_string(o.circle_s);
  for (const Case& c :
       {Case{"circle", {circle}},
        Case{"circle, per-scan insertion (mapper.batch_s=0)", {circle, "mapper.batch_s=0"}},
        Case{"loop", {"sim.path=loop", "sim.duration_s=" + std::to_string(o.loop_s)}}}) {
    const std::string name = std::string(c.name).substr(0, std::string(c.name).find(','));
    const std::string log_path = o.work + "/rig_b_" + name + ".lcmlog";
    const std::string out_dir = o.work + "/replay_rig_b_" + name;
    const SimulatedLog log = simulate(o, c.overrides, log_path, false);
    // The `sweepmap replay` command itself, so that its time includes start-up and its
    // peak RSS is its own.
    // --force: the scratch folder of an earlier bench is emptied, not refused.
    std::vector<std::string> args = {o.sweepmap_exe, "replay", log_path,     "--rig",  o.rig,
                                     "--out",        out_dir,  "--no-plots", "--force"};
    appendSetArguments(&args, c.overrides);
    const std::string log_txt = out_dir + ".txt";
    const ChildRun run = runChild(args, log_txt, log_txt);
    if (!run.ok) {
      out << "  " << c.name << ": replay failed (see " << log_txt << ")\n";
      continue;
    }
    const double wall_s = run.wall_s, cpu_s = run.cpu_s;
    const int64_t peak_kib = run.peak_kib;
    int64_t points = 0;
    try {
      std::ifstream f(out_dir + "/summary.json");
      points = nlohmann::json::parse(f).at("points").get<int64_t>();
    } catch (const std::exception&) {
      points = 0;
    }
    out << "  " << c.name << ": " << std::setprecision(1) << log.result.duration_s << " s, "
        << log.result.scans << " scans in " << std::setprecision(2) << wall_s
        << " s wall: real-time factor " << std::setprecision(1) << log.result.duration_s / wall_s
        << " (" << log.result.duration_s / cpu_s << " on its " << std::setprecision(2) << cpu_s
        << " CPU s), " << std::setprecision(0) << points / wall_s << " points/s, peak RSS "
        << std::setprecision(1) << peak_kib / 1024.0 << " MiB\n"
        << std::setprecision(2);
  }
}

}  // namespace

int benchRigB(const RigBBenchOptions& o, std::ostream& out) {
  std::filesystem::create_directories(o.work);
  out << std::fixed << std::setprecision(2);
  out << "rig B (" << o.rig << ", " << o.scene << ")\n";
  benchEkfInProcess(o, out);
  benchReplay(o, out);
  // Last: it moves this process into a private network namespace.
  benchOdometryProcess(o, out);
  return 0;
}

// Rig B's joint calibration on calib plan's drive (a figure-eight with stops) with every
// build error at its default, one per seed: its time, and each parameter's error against the
// truth in sigmas, and the room's size against the scene's.
void benchRigBCalibrationSeeds(const RigBBenchOptions& o, std::ostream& out) {
  out << "calib rig (rig B, joint), calib plan's drive ("
      << calibrationRecordingSimLine(RigKind::kMobileLidar)
      << "), every build error at its default:\n";
  const std::vector<std::string> drive = rigBRecordingSets(RigBRecording());  // the plan's
  for (int seed = 1; seed <= o.rig_calib_seeds; ++seed) {
    const std::string log_path = o.work + "/rig_b_joint_seed" + std::to_string(seed) + ".lcmlog";
    SimMobileOptions so;
    const SimSetup setup = loadSimSetup(o.rig, o.scene, drive);
    so.rig = requireKind<MobileLidarConfig>(setup.rig, "the rig-B bench");
    so.scene = setup.scene;
    so.seed = uint64_t(seed);
    EventLogWriter writer(log_path);
    simulateMobile(so, [&](const Message& m) { writer.write(m.utime, m.channel, m.data); });
    writer.close();
    MobileRigCalibRequest request;
    request.logs = {log_path};
    request.rig = o.rig;
    request.sets = drive;
    request.progress = false;
    const double cpu0 = cpuSeconds(RUSAGE_SELF);
    const auto t0 = Clock::now();
    const RigCalibration r = runMobileRigCalibration(request);
    out << "  seed " << seed << ": " << std::setprecision(1) << secondsSince(t0) << " s wall, "
        << cpuSeconds(RUSAGE_SELF) - cpu0 << " CPU s, residual RMS " << std::setprecision(2)
        << r.rms_before * 1e3 << " -> " << r.rms_after * 1e3 << " mm\n";
    for (const CalibParameter& p : r.parameters) {
      out << "    " << std::left << std::setw(32) << p.key << std::right << std::setprecision(6)
          << std::setw(12) << p.value << " +- " << std::setw(10) << p.sigma << " " << p.unit;
      if (!p.observable) out << "  (not observable)";
      if (p.truth) {
        out << "  error " << std::setw(10) << p.value - *p.truth;
        if (p.sigma > 0)
          out << " = " << std::setprecision(2) << (p.value - *p.truth) / p.sigma << " sigma";
      }
      out << "\n";
    }
    for (const CalibMeasure& m : r.measures) {
      out << "    " << std::left << std::setw(32) << m.key << std::right << std::setprecision(4)
          << std::setw(12) << m.value << " " << m.unit;
      if (m.truth) out << "  error " << std::setprecision(1) << (m.value - *m.truth) * 1e3 << " mm";
      out << "\n";
    }
    for (const std::string& w : r.warnings) out << "    warning: " << w << "\n";
  }
  out << std::setprecision(2);
}

}  // namespace sweepmap
