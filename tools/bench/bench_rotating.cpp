#include "tools/bench/bench_rotating.hpp"

#include <sys/resource.h>

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <optional>

#include "core/event_log.hpp"
#include "tools/offline/log_sweeps.hpp"
#include "tools/offline/replay.hpp"
#include "tools/offline/runs.hpp"
#include "tools/offline/simulation.hpp"

namespace sweepmap {
namespace {

double peakRssMiB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // ru_maxrss is in KiB on Linux
}

}  // namespace

int benchRotating(const RotatingBenchOptions& o, std::ostream& out) {
  using clock = std::chrono::steady_clock;
  std::filesystem::create_directories(o.work);
  for (int mode : {1, 7}) {
    SimOptions so;
    const SimSetup setup = loadSimSetup(o.rig, o.scene, {"motor.mode=" + std::to_string(mode)});
    so.rig = requireKind<RotatingLidarConfig>(setup.rig, "the rig-A bench");
    so.scene = setup.scene;
    so.sweeps = o.sweeps;
    const std::string log = o.work + "/bench_mode" + std::to_string(mode) + ".lcmlog";
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
    ro.out_dir = o.work + "/replay_mode" + std::to_string(mode);
    ro.plots = false;
    t0 = clock::now();
    const ReplayResult rr = replayLog(ro, so.rig);
    const double replay_s = std::chrono::duration<double>(clock::now() - t0).count();
    const double scan_time_s = o.sweeps * scanMode(mode).period_s;
    out << "mode " << mode << ": " << o.sweeps << " sweeps, " << sr.simulated_us / 1e6
        << " s simulated\n"
        << "  simulation  " << sim_s << " s wall, real-time factor "
        << sr.simulated_us / 1e6 / sim_s << "\n"
        << "  replay      " << replay_s << " s wall, real-time factor "
        << rr.log_duration_s / replay_s << " (log time), " << scan_time_s / replay_s
        << " (scan-window time), " << static_cast<int64_t>(rr.points / replay_s) << " points/s\n";

    // Plate correction of one sweep (beta, shape check, phi_offset, rotation of C_O'),
    // for both beta methods, on the first sweep of the log.
    std::optional<AssembledSweep> first;
    forEachSweep(log, so.rig, [&](const AssembledSweep& s, const SweepTruth&) {
      if (!first) first = s;
    });
    if (first) {
      for (const char* method : {"ray_plane", "centroid"}) {
        RotatingLidarConfig rig = so.rig;
        rig.plate.beta_method = method;
        const int reps = 20;
        AssembledSweep work = *first;
        t0 = clock::now();
        for (int k = 0; k < reps; ++k) correctSweep(rig, &work);
        const double ms =
            std::chrono::duration<double, std::milli>(clock::now() - t0).count() / reps;
        out << "  plate correction (" << method << ") " << ms << " ms per sweep of "
            << first->points_Op.size() << " points, " << first->plate_rays.size()
            << " plate-plane rays (C_O rotation included)\n";
      }
    }
  }
  out << "peak RSS " << peakRssMiB() << " MiB\n";
  return 0;
}

}  // namespace sweepmap
