#include <sys/resource.h>

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>

#include "core/event_log.hpp"
#include "tools/bench_mobile.hpp"
#include "tools/commands.hpp"
#include "tools/log_sweeps.hpp"
#include "tools/replay.hpp"
#include "tools/simulation.hpp"

namespace sweepmap {
namespace {

double peakRssMiB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // ru_maxrss is in KiB on Linux
}

}  // namespace

Runner addBenchCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "bench",
      "Measure simulation and offline replay speed (assembly + plate correction + OctoMap) as "
      "real-time factors for modes 1 and 7, points per second, one sweep's plate correction and "
      "peak memory; rig B: EKF updates per second, the CPU share of the sweepmap-odometry process "
      "at 100/200/400 Hz IMU (private network namespace), replay-mobile real-time factors on a "
      "circle and a lab loop. Prints figures; run on an idle machine, compare ratios within one run");
  struct Opts {
    std::string rig = "config/rig_a.yaml";
    std::string scene = "config/scene_conference_room.yaml";
    std::string work = "build/bench";
    int sweeps = 2;
    RigBBenchOptions rig_b;
    bool skip_a = false, skip_b = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("--rig", o->rig, "rig config")->capture_default_str()->check(CLI::ExistingFile);
  cmd->add_option("--scene", o->scene, "scene")->capture_default_str()->check(CLI::ExistingFile);
  cmd->add_option("--work", o->work, "scratch directory")->capture_default_str();
  cmd->add_option("--sweeps", o->sweeps, "sweeps per mode")->capture_default_str();
  cmd->add_option("--rig-b", o->rig_b.rig, "rig B config")->capture_default_str()->check(CLI::ExistingFile);
  cmd->add_option("--scene-b", o->rig_b.scene, "rig B scene")->capture_default_str()->check(CLI::ExistingFile);
  cmd->add_option("--odometry-feed-s", o->rig_b.process_feed_s,
                  "log time fed to sweepmap-odometry per IMU rate")->capture_default_str();
  cmd->add_flag("--skip-rig-a", o->skip_a, "leave out rig A");
  cmd->add_flag("--skip-rig-b", o->skip_b, "leave out rig B");
  return [o]() {
    namespace fs = std::filesystem;
    using clock = std::chrono::steady_clock;
    fs::create_directories(o->work);
    std::cout << std::fixed << std::setprecision(2);
    std::cout << "sweepmap bench (one thread; real-time factor = simulated or logged time / "
                 "wall time)\n";
    for (int mode : {1, 7}) {
      if (o->skip_a) break;
      SimOptions so;
      loadSimConfig(o->rig, o->scene, {"motor.mode=" + std::to_string(mode)}, &so.rig, &so.scene);
      so.sweeps = o->sweeps;
      const std::string log = o->work + "/bench_mode" + std::to_string(mode) + ".lcmlog";
      auto t0 = clock::now();
      SimResult sr;
      {
        EventLogWriter w(log);
        sr = simulate(so, [&](const Message& m) { w.write(m.utime, m.channel, m.data); });
        w.close();
      }
      const double sim_s = std::chrono::duration<double>(clock::now() - t0).count();

      ReplayOptions ro;
      ro.log_path = log;
      ro.out_dir = o->work + "/replay_mode" + std::to_string(mode);
      ro.plots = false;
      t0 = clock::now();
      const ReplayResult rr = replayLog(ro, so.rig);
      const double replay_s = std::chrono::duration<double>(clock::now() - t0).count();
      const double scan_time_s = o->sweeps * scanMode(mode).period_s;
      std::cout << "mode " << mode << ": " << o->sweeps << " sweeps, "
                << sr.simulated_us / 1e6 << " s simulated\n"
                << "  simulation  " << sim_s << " s wall, real-time factor "
                << sr.simulated_us / 1e6 / sim_s << "\n"
                << "  replay      " << replay_s << " s wall, real-time factor "
                << rr.log_duration_s / replay_s << " (log time), "
                << scan_time_s / replay_s << " (scan-window time), "
                << static_cast<int64_t>(rr.points / replay_s) << " points/s\n";

      // Plate correction of one sweep (beta, shape check, phi_offset, rotation of C_O'),
      // for both beta methods, on the first sweep of the log.
      std::optional<AssembledSweep> first;
      forEachSweep(log, so.rig, [&](const AssembledSweep& s, const SweepTruth&) {
        if (!first) first = s;
      });
      if (first) {
        for (const char* method : {"ray_plane", "centroid"}) {
          RigConfig rig = so.rig;
          rig.plate.beta_method = method;
          const int reps = 20;
          AssembledSweep work = *first;
          t0 = clock::now();
          for (int k = 0; k < reps; ++k) correctSweep(rig, &work);
          const double ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count() / reps;
          std::cout << "  plate correction (" << method << ") " << ms << " ms per sweep of "
                    << first->points_Op.size() << " points, " << first->plate_rays.size()
                    << " plate-plane rays (C_O rotation included)\n";
        }
      }
    }
    if (!o->skip_a) std::cout << "peak RSS " << peakRssMiB() << " MiB\n";
    if (!o->skip_b) {
      o->rig_b.work = o->work;
      std::error_code ec;
      const fs::path self = fs::read_symlink("/proc/self/exe", ec);
      o->rig_b.sweepmap_exe = self.string();
      if (!ec && fs::exists(self.parent_path() / "sweepmap-odometry")) {
        o->rig_b.bin_dir = self.parent_path().string();
      }
      benchRigB(o->rig_b, std::cout);
    }
    return 0;
  };
}

}  // namespace sweepmap
