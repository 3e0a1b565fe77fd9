#include "tools/replay.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "calib/rotating_geometry.hpp"
#include "core/event_log.hpp"
#include "drivers/shaft_trajectory.hpp"
#include "mapping/cloud_io.hpp"
#include "mapping/occupancy_map.hpp"
#include "mapping/plot.hpp"
#include "processes/assembler_node.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/mapper_node.hpp"
#include "processes/offline_bus.hpp"
#include "sweepmap/truth_rig_t.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;
constexpr double kRadToDeg = 180.0 / M_PI;

// Rounds for JSON so the file is stable and readable (values are far from these limits).
double round6(double v) { return std::round(v * 1e6) / 1e6; }

class ProgressBar {
 public:
  ProgressBar(bool enabled, uint64_t total) : enabled_(enabled && isatty(2)), total_(total) {}
  void update(uint64_t done) {
    if (!enabled_ || total_ == 0) return;
    const int pct = static_cast<int>(100 * done / total_);
    if (pct == last_) return;
    last_ = pct;
    const int width = 40;
    const int fill = pct * width / 100;
    std::fprintf(stderr, "\rreplay [%s%s] %3d%%", std::string(fill, '#').c_str(),
                 std::string(width - fill, ' ').c_str(), pct);
    std::fflush(stderr);
  }
  ~ProgressBar() {
    if (enabled_ && last_ >= 0) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  uint64_t total_;
  int last_ = -1;
};

}  // namespace

ReplayResult replayLog(const ReplayOptions& options, const RigConfig& rig) {
  ReplayResult result;
  EventLogReader reader(options.log_path);  // throws when it cannot be opened
  const fs::path out(options.out_dir);
  fs::create_directories(out / "sweeps");

  EventLogWriter derived((out / "derived.lcmlog").string());
  OfflineBus bus;
  AssemblerNode assembler(rig);
  MapperNode mapper(rig.mapper, (out / "map.bt").string());
  bus.attach(&assembler);
  bus.attach(&mapper);
  bus.setSink([&](const Message& m) { derived.write(m.utime, m.channel, m.data); });

  ShaftTrajectory truth;
  bool have_truth_rig = false;
  truth_rig_t truth_rig;
  nlohmann::json sweeps = nlohmann::json::array();
  std::vector<Eigen::Vector3f> first_Op, first_O;

  assembler.setSweepObserver([&](const AssembledSweep& s) {
    std::ostringstream name;
    name << "sweep_" << std::setw(6) << std::setfill('0') << s.window.sweep_id;
    writePcdBinary((out / "sweeps" / (name.str() + ".pcd")).string(), s.points);
    writePlyBinary((out / "sweeps" / (name.str() + ".ply")).string(), s.points);
    nlohmann::json j;
    j["id"] = s.window.sweep_id;
    j["mode"] = s.window.mode;
    j["scans"] = s.scans;
    j["points"] = s.points.size();
    j["plate_points"] = s.plate.points;
    j["beta_deg"] = s.plate.found ? nlohmann::json(round6(s.plate.beta_rad * kRadToDeg))
                                  : nlohmann::json(nullptr);
    j["phi_offset_deg"] = round6(s.phi_offset_rad * kRadToDeg);
    j["corrected"] = s.corrected;
    j["reason"] = s.reason;
    if (truth.covers(s.first_ray_utime)) {
      // Frame O' is the lidar frame at the window's first ray: the true phi_offset is the
      // true shaft angle then (0 = X_L along the rig's front).
      const double phi_true = rotating::wrapAngle(truth.angleAt(s.first_ray_utime));
      j["phi_true_deg"] = round6(phi_true * kRadToDeg);
      j["phi_error_deg"] =
          round6(rotating::wrapAngle(s.phi_offset_rad - phi_true) * kRadToDeg);
    }
    sweeps.push_back(j);
    result.points += static_cast<int64_t>(s.points.size());
    ++result.sweeps;
    if (result.sweeps == 1) {
      first_Op = s.points_Op;
      first_O = s.points;
    }
  });

  std::map<std::string, int64_t> skipped;
  const std::set<std::string> known = {channels::kLidarScan, channels::kScanWindow,
                                       channels::kTruthShaft, channels::kTruthRig};
  ProgressBar bar(options.progress, reader.size());
  LogEvent ev;
  int64_t first_utime = 0, last_utime = 0;
  int64_t now = 0;
  try {
    while (reader.next(&ev)) {
      ++result.events;
      if (result.events == 1) first_utime = ev.utime;
      last_utime = ev.utime;
      now = std::max(now, ev.utime);
      bar.update(reader.offset());
      if (!known.count(ev.channel)) {
        ++skipped[ev.channel];
        continue;
      }
      Message m{ev.utime, ev.channel, std::move(ev.data)};
      if (m.channel == channels::kTruthShaft) {
        truth_shaft_t t;
        if (decodeMessage(m, &t)) truth.apply(fromLcm(t));
        continue;
      }
      if (m.channel == channels::kTruthRig) {
        have_truth_rig = decodeMessage(m, &truth_rig) || have_truth_rig;
        continue;
      }
      bus.tick(now);
      bus.deliver(m);
    }
  } catch (const LogError& e) {
    result.log_error = true;
    result.error = e.what();
  }
  // Keep what was produced: a sweep whose window closed is assembled, the map saved.
  if (!result.log_error) bus.finish(now);
  else {
    Outbox o;
    mapper.finish(now, o);
    for (auto& m : o.take()) derived.write(m.utime, m.channel, m.data);
  }
  derived.close();

  nlohmann::json summary;
  summary["log"] = fs::path(options.log_path).filename().string();
  summary["events"] = result.events;
  summary["sweeps"] = sweeps;
  const MapStats st = mapper.map().stats();
  summary["map"] = {{"resolution_m", st.resolution_m},
                    {"occupied_voxels", st.occupied_voxels},
                    {"free_voxels", st.free_voxels},
                    {"sweeps_inserted", assembler.counter("sweeps")}};
  summary["skipped_channels"] = skipped;
  summary["assembler"] = {{"scans", assembler.counter("scans")},
                          {"invalid", assembler.counter("invalid")},
                          {"dropped", assembler.counter("dropped")}};
  if (have_truth_rig) {
    summary["truth"] = {{"alpha_true_deg", round6(truth_rig.alpha_true_rad * kRadToDeg)},
                        {"scene", truth_rig.scene}};
  }
  if (result.log_error) summary["error"] = result.error;
  {
    const std::string tmp = (out / "summary.json.tmp").string();
    std::ofstream f(tmp);
    f << summary.dump(2) << "\n";
    f.close();
    fs::rename(tmp, out / "summary.json");
  }
  result.log_duration_s = 1e-6 * static_cast<double>(last_utime - first_utime);

  if (options.plots && !first_O.empty()) {
    PlotOptions po;
    po.title = "Sweep 0, top view (z between -0.3 and 1.0 m): uncorrected C_O' and corrected C_O";
    po.z_band_m = PlotRange{-0.3, 1.0};
    try {
      plotTopView((out / "top_view.png").string(),
                  {{"uncorrected C_O'", "red", first_Op}, {"corrected C_O", "blue", first_O}},
                  po);
    } catch (const std::exception& e) {
      std::cerr << "replay: top view not drawn: " << e.what() << "\n";
    }
  }
  return result;
}

}  // namespace sweepmap
