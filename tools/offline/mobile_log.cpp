#include "tools/offline/mobile_log.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/odometry_node.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"
#include "tools/offline/log_player.hpp"

namespace sweepmap {
namespace {

void addPose(const Message& m, PoseTrack* track) {
  pose2d_t p;
  if (decodeMessage(m, &p) && std::isfinite(p.x_m) && std::isfinite(p.y_m) &&
      std::isfinite(p.theta_rad)) {
    track->add(p.utime, {p.x_m, p.y_m, p.theta_rad});
  }
}

}  // namespace

MobileLog loadMobileLog(const std::string& path, const MobileLidarConfig& rig) {
  MobileLog log;
  LogPlayer player(path);
  OdometryNode odometry(rig.odometry);
  player.bus().attach(&odometry);
  player.bus().setSink([&](const Message& m) {
    if (m.channel == channels::kOdometryPose) addPose(m, &log.ekf);
    if (m.channel == channels::kWheelOdometry) addPose(m, &log.wheels);
  });
  player.addInputs({channels::kWheelTicks, channels::kImu});
  player.handle(channels::kLidarScan, [&](const Message& msg) {
    lidar_scan_t m;
    if (!decodeMessage(msg, &m)) {
      ++log.invalid_scans;
      return;
    }
    Scan2D scan = fromLcm(m);
    if (!validateScan(scan, rig.assembler.beam_count).empty()) {
      ++log.invalid_scans;
      return;
    }
    rig.assembler.toOdometryClock(&scan);
    log.scans.push_back(std::move(scan));
  });
  player.handle(channels::kTruthPose, [&](const Message& m) { addPose(m, &log.truth); });
  player.handle(channels::kTruthMounting, [&](const Message& m) {
    truth_mounting_t t;
    if (!log.truth_mounting && decodeMessage(m, &t)) log.truth_mounting = t;
  });
  player.handle(channels::kTruthMobileRig, [&](const Message& m) {
    truth_mobile_rig_t t;
    if (!log.truth_rig && decodeMessage(m, &t)) log.truth_rig = t;
  });
  const LogPlayResult played = player.play();
  log.log_error = played.log_error;
  log.error = played.error;
  player.finish();
  log.gated_wheel_readings = odometry.ekf().counters().gated_wheels;
  log.ekf_gyro_bias_rad_s = odometry.ekf().state()[OdometryEkf::kBias];
  log.ekf_gyro_bias_sigma_rad_s =
      std::sqrt(std::max(0.0, odometry.ekf().covariance()(OdometryEkf::kBias, OdometryEkf::kBias)));
  return log;
}

OdometryReadings loadOdometryReadings(const std::string& path) {
  OdometryReadings out;
  LogPlayer player(path);
  player.handle(channels::kWheelTicks, [&](const Message& m) {
    wheel_ticks_t t;
    if (decodeMessage(m, &t)) out.wheels.push_back({t.utime, t.left_ticks, t.right_ticks});
  });
  player.handle(channels::kImu, [&](const Message& m) {
    imu_t t;
    if (decodeMessage(m, &t) && std::isfinite(t.gyro_rad_s[2]))
      out.gyro.push_back({t.utime, t.gyro_rad_s[2]});
  });
  player.play();
  const auto by_time = [](const auto& a, const auto& b) { return a.utime < b.utime; };
  std::stable_sort(out.wheels.begin(), out.wheels.end(), by_time);
  std::stable_sort(out.gyro.begin(), out.gyro.end(), by_time);
  return out;
}

std::vector<Eigen::Vector3f> assembleWorld(const MobileLog& log, const PoseTrack& track,
                                           const LidarMounting& mounting,
                                           std::vector<int>* scan_of_point) {
  std::vector<Eigen::Vector3f> cloud;
  if (scan_of_point) scan_of_point->clear();
  const Eigen::Isometry3d T_BL = mounting.T_BL();
  for (size_t j = 0; j < log.scans.size(); ++j) {
    const auto pts = scanToWorld(log.scans[j], track, T_BL);
    cloud.insert(cloud.end(), pts.begin(), pts.end());
    if (scan_of_point) scan_of_point->insert(scan_of_point->end(), pts.size(), static_cast<int>(j));
  }
  return cloud;
}

LidarMounting trueMounting(const truth_mounting_t& t) {
  LidarMounting m;
  m.nominal_rpy_rad =
      Eigen::Vector3d(t.nominal_rpy_rad[0], t.nominal_rpy_rad[1], t.nominal_rpy_rad[2]);
  m.gamma_rad = t.gamma_true_rad;
  m.beta_rad = t.beta_true_rad;
  m.alpha_rad = t.alpha_true_rad;
  m.t_BL_m = Eigen::Vector3d(t.t_BL_m[0], t.t_BL_m[1], t.t_BL_m[2]);
  return m;
}

std::string mountingResultJsonText(const MountingCalibrationResult& r,
                                   const std::optional<LidarMounting>& truth) {
  nlohmann::json j = {{"method", mountingMethodName(r.method)},
                      {"ok", r.ok},
                      {"gamma_rad", r.gamma_rad},
                      {"beta_rad", r.beta_rad},
                      {"alpha_rad", r.alpha_rad},
                      {"time_offset_s", r.time_offset_s},
                      {"track_drift_m_s", {r.drift_x_m_s, r.drift_y_m_s}},
                      {"residual_before_m", r.residual_before_m},
                      {"residual_after_m", r.residual_after_m},
                      {"correspondences", r.correspondences},
                      {"iterations", r.iterations}};
  if (!r.ok) j["reason"] = r.reason;
  if (r.ok && r.sigma_gamma_rad > 0.0) {  // the fast solver's, from its covariance
    j["sigma"] = {{"gamma_rad", r.sigma_gamma_rad},
                  {"beta_rad", r.sigma_beta_rad},
                  {"alpha_rad", r.sigma_alpha_rad}};
    if (r.sigma_time_offset_s > 0.0) j["sigma"]["time_offset_s"] = r.sigma_time_offset_s;
  }
  if (truth && r.ok) {
    j["error_mrad"] = {{"gamma", 1e3 * (r.gamma_rad - truth->gamma_rad)},
                       {"beta", 1e3 * (r.beta_rad - truth->beta_rad)},
                       {"alpha", 1e3 * (r.alpha_rad - truth->alpha_rad)}};
  }
  return j.dump();
}

}  // namespace sweepmap
