#include "tools/offline/replay_profile.hpp"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "core/atomic_file.hpp"
#include "core/event_log.hpp"
#include "core/progress.hpp"
#include "mapping/cloud_io.hpp"
#include "mapping/occupancy_map.hpp"
#include "mapping/plot.hpp"
#include "processes/channels.hpp"
#include "processes/mapper_node.hpp"
#include "processes/profile_assembler_node.hpp"
#include "tools/offline/log_player.hpp"
#include "tools/offline/views_3d.hpp"

namespace sweepmap {

namespace fs = std::filesystem;

namespace {

struct Sweep {
  int64_t profiles = 0;
  std::vector<Eigen::Vector3f> points;  // [m], O_r
};

void writeClouds(const fs::path& out, const std::map<int32_t, Sweep>& sweeps) {
  fs::create_directories(out / "sweeps");
  std::vector<Eigen::Vector3f> all;
  for (const auto& [id, sweep] : sweeps) {
    char name[32];
    std::snprintf(name, sizeof name, "sweep_%06d", id);
    writePcdAndPly((out / "sweeps" / name).string(), sweep.points);
    all.insert(all.end(), sweep.points.begin(), sweep.points.end());
  }
  writePcdAndPly((out / "cloud").string(), all);
}

void writeSummary(const fs::path& out, const std::string& log_path, const ProfileGeometry& g,
                  const std::map<int32_t, Sweep>& sweeps, const ProfileReplayResult& r,
                  const LogPlayResult& played, const MapperNode& mapper) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [id, sweep] : sweeps) {
    list.push_back({{"id", id}, {"profiles", sweep.profiles}, {"points", sweep.points.size()}});
  }
  nlohmann::json s;
  s["log"] = fs::path(log_path).filename().string();
  s["events"] = r.events;
  s["profiles"] = r.profiles;
  s["invalid_profiles"] = r.invalid;
  s["points"] = r.points;
  s["sweeps"] = list;
  s["skipped_channels"] = played.skipped_channels;
  s["geometry"] = {{"m_mm", g.m_mm},
                   {"n_mm", g.n_mm},
                   {"laser_tilt_rad", g.laser_tilt_rad},
                   {"encoder_zero_rad", g.encoder_zero_rad}};
  const MapStats st = mapper.map().stats();
  s["map"] = {{"resolution_m", st.resolution_m},
              {"occupied_voxels", st.occupied_voxels},
              {"free_voxels", st.free_voxels}};
  if (r.log_error) s["error"] = r.error;
  writeFileAtomic((out / "summary.json").string(), s.dump(2) + "\n");
}

// Every sweep's points together.
std::vector<Eigen::Vector3f> allPoints(const std::map<int32_t, Sweep>& sweeps) {
  std::vector<Eigen::Vector3f> all;
  for (const auto& [id, sweep] : sweeps)
    all.insert(all.end(), sweep.points.begin(), sweep.points.end());
  return all;
}

// Top view of the cloud coloured by height (a top view of a turntable scan shows nothing of
// the heights otherwise: plates and test pieces are told apart by them).
void plotTopViewOf(const fs::path& out, const std::map<int32_t, Sweep>& sweeps) {
  std::vector<Layer> layers = {
      {std::to_string(sweeps.size()) + " sweeps", "", allPoints(sweeps), true}};
  PlotOptions po;
  po.title = "Top view: the profiles in the turntable's frame O_r, coloured by height";
  po.point_size = 0.2;
  try {
    plotTopView((out / "top_view.png").string(), layers, po);
  } catch (const std::exception& e) {
    std::cerr << "replay: top view not drawn: " << e.what() << "\n";
  }
}

}  // namespace

ProfileReplayResult replayProfileLog(const std::string& log_path, const RotatingProfileConfig& rig,
                                     const std::string& out_dir, bool plots, bool progress) {
  LogPlayer player(log_path);
  ProgressOptions po;
  po.enabled = progress;
  Progress bar("replay", po);
  player.setProgress([&bar](uint64_t offset, uint64_t size) {
    bar.update(size > 0 ? static_cast<double>(offset) / static_cast<double>(size) : -1.0);
  });
  const fs::path out(out_dir);
  fs::create_directories(out);
  EventLogWriter derived((out / "derived.lcmlog").string());
  ProfileAssemblerNode assembler(rig.geometry.toGeometry());
  MapperNode mapper(rig.mapper, (out / "map.bt").string());
  std::map<int32_t, Sweep> sweeps;
  assembler.setObserver([&](const Profile& p, const std::vector<Eigen::Vector3f>& points) {
    Sweep& sweep = sweeps[p.sweep_id];
    ++sweep.profiles;
    sweep.points.insert(sweep.points.end(), points.begin(), points.end());
  });
  player.bus().attach(&assembler);
  player.bus().attach(&mapper);
  player.bus().setSink([&](const Message& m) { derived.write(m.utime, m.channel, m.data); });
  player.addInputs({channels::kProfile});
  const LogPlayResult played = player.play();
  player.finish();
  derived.close();

  ProfileReplayResult r;
  r.events = played.events;
  r.log_error = played.log_error;
  r.error = played.error;
  r.profiles = assembler.counter("profiles");
  r.invalid = assembler.counter("invalid") + assembler.counter("dropped");
  r.points = assembler.counter("points");
  r.sweeps = static_cast<int>(sweeps.size());
  writeClouds(out, sweeps);
  writeSummary(out, log_path, assembler.geometry(), sweeps, r, played, mapper);
  if (plots && !sweeps.empty()) {
    plotTopViewOf(out, sweeps);
    drawViews3d(out, "replay", "rig C replay", "O_r", allPoints(sweeps),
                mapper.map().occupiedCentres(), rig.mapper.resolution_m);
  }
  return r;
}

}  // namespace sweepmap
