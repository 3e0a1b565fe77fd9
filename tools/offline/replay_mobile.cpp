#include "tools/offline/replay_mobile.hpp"

#include <cmath>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "core/angles.hpp"
#include "core/atomic_file.hpp"
#include "core/event_log.hpp"
#include "core/progress.hpp"
#include "mapping/cloud_io.hpp"
#include "mapping/occupancy_map.hpp"
#include "mapping/plot.hpp"
#include "processes/channels.hpp"
#include "processes/mapper_node.hpp"
#include "processes/odometry_node.hpp"
#include "processes/world_assembler_node.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "tools/offline/log_player.hpp"
#include "tools/offline/views_3d.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

// What the replay collects besides the nodes' own outputs: the world cloud and both paths.
struct Collected {
  std::vector<Eigen::Vector3f> cloud;
  std::vector<float> intensity;  // one per cloud point while with_intensity
  bool with_intensity = true;    // every scan so far had intensities
  std::vector<Eigen::Vector3f> ekf_path, odo_path;
};

void collectPath(const Message& m, Collected* c) {
  if (m.channel != channels::kOdometryPose && m.channel != channels::kWheelOdometry) return;
  pose2d_t p;
  if (decodeMessage(m, &p)) {
    (m.channel == channels::kOdometryPose ? c->ekf_path : c->odo_path)
        .emplace_back(static_cast<float>(p.x_m), static_cast<float>(p.y_m), 0.0f);
  }
}

double pathLength(const std::vector<Eigen::Vector3f>& p) {
  double l = 0;
  for (size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
  return l;
}

void writeSummary(const fs::path& out, const std::string& log_path, const LogPlayResult& played,
                  const MobileReplayResult& result, const OdometryNode& odometry,
                  const WorldAssemblerNode& assembler, const MapperNode& mapper,
                  const Collected& c) {
  nlohmann::json s;
  s["log"] = fs::path(log_path).filename().string();
  s["events"] = result.events;
  s["scans"] = result.scans;
  s["points"] = result.points;
  s["skipped_channels"] = played.skipped_channels;
  s["odometry"] = {{"wheel_readings_fused", odometry.ekf().counters().wheels},
                   {"wheel_readings_gated", odometry.ekf().counters().gated_wheels},
                   {"gyro_fused", odometry.ekf().counters().gyro},
                   {"invalid", odometry.counter("invalid")},
                   {"path_length_m_ekf", roundTo(pathLength(c.ekf_path), 3)},
                   {"path_length_m_wheels", roundTo(pathLength(c.odo_path), 3)},
                   {"trusted_at_end", odometry.ekf().trusted()}};
  const MapStats st = mapper.map().stats();
  s["map"] = {{"resolution_m", st.resolution_m},
              {"occupied_voxels", st.occupied_voxels},
              {"free_voxels", st.free_voxels}};
  s["assembler"] = {{"rays_without_pose", assembler.counter("rays_without_pose")},
                    {"invalid", assembler.counter("invalid")}};
  if (result.log_error) s["error"] = result.error;
  writeFileAtomic((out / "summary.json").string(), s.dump(2) + "\n");
}

// The walls between floor and ceiling, coloured by height, and the paths drawn at the band's
// middle (they are at z = 0, below it).
void plotTopViewOf(const fs::path& out, const Collected& c) {
  PlotOptions po;
  po.point_size = 0.2;
  const ZBand band = wallBand(c.cloud);
  std::vector<Eigen::Vector3f> odo = c.odo_path, ekf = c.ekf_path;
  if (band.valid) {
    po.z_band_m = PlotRange{band.min, band.max};
    for (auto* path : {&odo, &ekf}) {
      for (auto& p : *path) p.z() = static_cast<float>(0.5 * (band.min + band.max));
    }
  }
  char title[160];
  std::snprintf(title, sizeof title,
                "Top view between floor and ceiling (z %.2f to %.2f m): the cloud by height, "
                "the EKF and wheel-odometry paths",
                band.min, band.max);
  po.title =
      band.valid ? title : "Top view: the world-frame cloud, the EKF and wheel-odometry paths";
  try {
    plotTopView(
        (out / "top_view.png").string(),
        {{"cloud", "", c.cloud, true}, {"wheel odometry", "red", odo}, {"EKF", "blue", ekf}}, po);
  } catch (const std::exception& e) {
    std::cerr << "replay: top view not drawn: " << e.what() << "\n";
  }
}

}  // namespace

MobileReplayResult replayMobileLog(const std::string& log_path, const MobileLidarConfig& rig,
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

  OdometryNode odometry(rig.odometry);
  WorldAssemblerNode assembler(rig.assembler, rig.mounting.toMounting());
  MapperNode mapper(rig.mapper, (out / "map.bt").string());
  Collected c;
  assembler.setObserver([&](int64_t, const std::vector<Eigen::Vector3f>& pts,
                            const std::vector<float>& intensity, const Eigen::Vector3d&) {
    // Intensities for the whole cloud only while every scan has them.
    c.with_intensity = c.with_intensity && intensity.size() == pts.size();
    c.cloud.insert(c.cloud.end(), pts.begin(), pts.end());
    if (c.with_intensity) c.intensity.insert(c.intensity.end(), intensity.begin(), intensity.end());
  });
  player.bus().attach(&odometry);
  player.bus().attach(&assembler);
  player.bus().attach(&mapper);
  player.bus().setSink([&](const Message& m) {
    derived.write(m.utime, m.channel, m.data);
    collectPath(m, &c);
  });
  player.addInputs({channels::kWheelTicks, channels::kImu, channels::kLidarScan});

  const LogPlayResult played = player.play();
  player.finish();
  derived.close();
  MobileReplayResult result;
  result.events = played.events;
  result.log_error = played.log_error;
  result.error = played.error;
  result.scans = assembler.counter("scans");
  result.points = static_cast<int64_t>(c.cloud.size());
  if (!c.with_intensity) c.intensity.clear();
  writePcdAndPly((out / "cloud").string(), c.cloud, c.intensity);
  writeSummary(out, log_path, played, result, odometry, assembler, mapper, c);
  if (plots && !c.cloud.empty()) {
    plotTopViewOf(out, c);
    drawViews3d(out, "replay", "rig B replay", "world", c.cloud, mapper.map().occupiedCentres(),
                rig.mapper.resolution_m, true);
  }
  return result;
}

}  // namespace sweepmap
