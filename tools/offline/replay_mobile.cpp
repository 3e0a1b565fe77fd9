#include "tools/offline/replay_mobile.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>

#include "core/event_log.hpp"
#include "mapping/cloud_io.hpp"
#include "mapping/occupancy_map.hpp"
#include "mapping/plot.hpp"
#include "processes/channels.hpp"
#include "processes/mapper_node.hpp"
#include "processes/offline_bus.hpp"
#include "processes/odometry_node.hpp"
#include "processes/world_assembler_node.hpp"
#include "sweepmap/pose2d_t.hpp"

namespace sweepmap {

MobileReplayResult replayMobileLog(const std::string& log_path, const MobileLidarConfig& rig,
                                   const std::string& out_dir, bool plots) {
  namespace fs = std::filesystem;
  MobileReplayResult result;
  EventLogReader reader(log_path);
  const fs::path out(out_dir);
  fs::create_directories(out);
  EventLogWriter derived((out / "derived.lcmlog").string());

  OdometryNode odometry(rig.odometry);
  WorldAssemblerNode assembler(rig.assembler, rig.mounting.toMounting());
  MapperNode mapper(rig.mapper, (out / "map.bt").string());
  std::vector<Eigen::Vector3f> cloud;
  std::vector<Eigen::Vector3f> ekf_path, odo_path;
  assembler.setObserver([&](int64_t, const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3d&) {
    cloud.insert(cloud.end(), pts.begin(), pts.end());
  });
  OfflineBus bus;
  bus.attach(&odometry);
  bus.attach(&assembler);
  bus.attach(&mapper);
  bus.setSink([&](const Message& m) {
    derived.write(m.utime, m.channel, m.data);
    if (m.channel == channels::kOdometryPose || m.channel == channels::kWheelOdometry) {
      pose2d_t p;
      if (decodeMessage(m, &p)) {
        (m.channel == channels::kOdometryPose ? ekf_path : odo_path)
            .emplace_back(static_cast<float>(p.x_m), static_cast<float>(p.y_m), 0.0f);
      }
    }
  });

  const std::set<std::string> inputs = {channels::kWheelTicks, channels::kImu, channels::kLidarScan};
  std::map<std::string, int64_t> skipped;
  LogEvent ev;
  int64_t now = 0;
  try {
    while (reader.next(&ev)) {
      ++result.events;
      now = std::max(now, ev.utime);
      if (!inputs.count(ev.channel)) {
        ++skipped[ev.channel];
        continue;
      }
      bus.tick(now);
      bus.deliver(Message{ev.utime, ev.channel, std::move(ev.data)});
    }
  } catch (const LogError& e) {
    result.log_error = true;
    result.error = e.what();
  }
  bus.finish(now);
  derived.close();
  result.scans = assembler.counter("scans");
  result.points = static_cast<int64_t>(cloud.size());
  writePcdBinary((out / "cloud.pcd").string(), cloud);

  const auto pathLength = [](const std::vector<Eigen::Vector3f>& p) {
    double l = 0;
    for (size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
    return l;
  };
  nlohmann::json s;
  s["log"] = fs::path(log_path).filename().string();
  s["events"] = result.events;
  s["scans"] = result.scans;
  s["points"] = result.points;
  s["skipped_channels"] = skipped;
  s["odometry"] = {{"wheel_readings_fused", odometry.ekf().counters().wheels},
                   {"wheel_readings_gated", odometry.ekf().counters().gated_wheels},
                   {"gyro_fused", odometry.ekf().counters().gyro},
                   {"invalid", odometry.counter("invalid")},
                   {"path_length_m_ekf", std::round(pathLength(ekf_path) * 1e3) / 1e3},
                   {"path_length_m_wheels", std::round(pathLength(odo_path) * 1e3) / 1e3},
                   {"trusted_at_end", odometry.ekf().trusted()}};
  const MapStats st = mapper.map().stats();
  s["map"] = {{"resolution_m", st.resolution_m}, {"occupied_voxels", st.occupied_voxels},
              {"free_voxels", st.free_voxels}};
  s["assembler"] = {{"rays_without_pose", assembler.counter("rays_without_pose")},
                    {"invalid", assembler.counter("invalid")}};
  if (result.log_error) s["error"] = result.error;
  {
    std::ofstream f(out / "summary.json.tmp");
    f << s.dump(2) << "\n";
    f.close();
    fs::rename(out / "summary.json.tmp", out / "summary.json");
  }
  if (plots && !cloud.empty()) {
    PlotOptions po;
    po.title = "Top view: world-frame cloud, EKF path (blue) and wheel-odometry path (red)";
    po.point_size = 0.2;
    try {
      plotTopView((out / "top_view.png").string(),
                  {{"cloud", "gray50", cloud},
                   {"wheel odometry", "red", odo_path},
                   {"EKF", "blue", ekf_path}},
                  po);
    } catch (const std::exception& e) {
      std::cerr << "replay: top view not drawn: " << e.what() << "\n";
    }
  }
  return result;
}

}  // namespace sweepmap
