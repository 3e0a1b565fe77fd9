#include "tools/offline/sim_mobile.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/rig_components.hpp"
#include "drivers/sim_mobile.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/sim_setup.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/truth_mounting_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"
#include "tools/offline/simulation.hpp"

namespace sweepmap {

void prepareSimMobileConfig(const std::string& rig_path, MobileLidarConfig* rig) {
  if (!rig->sim.path_file.empty() && std::filesystem::path(rig->sim.path_file).is_relative()) {
    rig->sim.path_file =
        (std::filesystem::path(rig_path).parent_path() / rig->sim.path_file).string();
  }
  rig->sim.validate(rig_path);
}

namespace {

// One stream's event in the merged log: its time, its stream (the tie-break at equal
// times) and its index in that stream.
struct Stamped {
  int64_t utime;
  int order;  // -1 TRUTH_MOUNTING, 0 TRUTH_POSE, 1 WHEEL_TICKS, 2 IMU, 3 LIDAR_SCAN
  size_t index;
};

truth_mounting_t truthMounting(const SimMobileOptions& options, const SimMobile& car,
                               const LidarMounting& nominal, int64_t utime) {
  const MobileLidarConfig& rig = options.rig;
  truth_mounting_t m{};
  m.utime = utime;
  m.gamma_true_rad = rig.sim.gamma_true_rad;
  m.beta_true_rad = rig.sim.beta_true_rad;
  m.alpha_true_rad = rig.sim.alpha_true_rad;
  const Eigen::Isometry3d W = car.T_room_world();
  for (int k = 0; k < 3; ++k) {
    m.nominal_rpy_rad[k] = nominal.nominal_rpy_rad[k];
    m.t_BL_m[k] = nominal.t_BL_m[k];
  }
  m.world_in_room[0] = W.translation().x();
  m.world_in_room[1] = W.translation().y();
  m.world_in_room[2] = std::atan2(W.linear()(1, 0), W.linear()(0, 0));
  m.room_size_m[0] = options.scene.room_length_m;
  m.room_size_m[1] = options.scene.room_width_m;
  m.room_size_m[2] = options.scene.room_height_m;
  m.scene = options.scene.name;
  return m;
}

pose2d_t truthPose(const TruthPose& t) {
  pose2d_t m{};
  m.utime = t.utime;
  m.x_m = t.pose.x_m;
  m.y_m = t.pose.y_m;
  m.theta_rad = t.pose.theta_rad;
  m.v_m_s = t.v_m_s;
  m.w_rad_s = t.w_rad_s;
  m.gyro_bias_rad_s = t.gyro_bias_rad_s;
  m.trusted = true;
  return m;
}

imu_t imuMessage(const ImuSample& s) {
  imu_t m{};
  m.utime = s.utime;
  for (int k = 0; k < 3; ++k) {
    m.gyro_rad_s[k] = s.gyro[k];
    m.accel_m_s2[k] = s.accel[k];
    m.rpy_rad[k] = s.rpy[k];
  }
  return m;
}

}  // namespace

SimMobileResult simulateMobile(const SimMobileOptions& options,
                               const std::function<void(const Message&)>& sink) {
  const MobileLidarConfig& rig = options.rig;
  const Scene scene(options.scene, PlateConfig{});
  const int64_t t0 = kSimEpochUtime;
  WheelGeometry wheels;
  wheels.radius_m = rig.odometry.wheel_radius_m;
  wheels.ticks_per_revolution = rig.odometry.ticks_per_revolution;
  wheels.wheel_distance_m = rig.odometry.ekf.wheel_distance_m;
  const LidarMounting nominal = rig.mounting.toMounting();
  SimMobile car(rig.sim, wheels, nominal.nominal_rpy_rad, nominal.t_BL_m, scene, options.seed, t0);

  // Each stream is generated whole, then the streams are merged by event time.
  std::vector<Stamped> events;
  const auto truth = car.truth();
  // TRUTH_MOUNTING at start and at 1 Hz (order -1: before anything else at the same time).
  const int64_t truth_mounting_count = static_cast<int64_t>(std::floor(rig.sim.duration_s)) + 1;
  for (int64_t i = 0; i < truth_mounting_count; ++i) {
    events.push_back({t0 + i * 1000000, -1, static_cast<size_t>(i)});
  }
  const auto ticks = car.wheelTicks();
  const auto imu = car.imu();
  const auto scans = car.scans();
  for (size_t i = 0; i < truth.size(); ++i) events.push_back({truth[i].utime, 0, i});
  for (size_t i = 0; i < ticks.size(); ++i) events.push_back({ticks[i].utime, 1, i});
  for (size_t i = 0; i < imu.size(); ++i) events.push_back({imu[i].utime, 2, i});
  for (size_t i = 0; i < scans.size(); ++i)
    events.push_back({car.scanDeliveryUtime(scans[i]), 3, i});
  std::stable_sort(events.begin(), events.end(), [](const Stamped& a, const Stamped& b) {
    return a.utime != b.utime ? a.utime < b.utime : a.order < b.order;
  });

  SimMobileResult result;
  for (const Stamped& e : events) {
    Outbox out;
    if (e.order == -1) {
      out.publish(channels::kTruthMounting, e.utime, truthMounting(options, car, nominal, e.utime));
    } else if (e.order == 0) {
      out.publish(channels::kTruthPose, e.utime, truthPose(truth[e.index]));
    } else if (e.order == 1) {
      wheel_ticks_t m{};
      m.utime = ticks[e.index].utime;
      m.left_ticks = ticks[e.index].left;
      m.right_ticks = ticks[e.index].right;
      out.publish(channels::kWheelTicks, e.utime, m);
    } else if (e.order == 2) {
      out.publish(channels::kImu, e.utime, imuMessage(imu[e.index]));
    } else {
      out.publish(channels::kLidarScan, e.utime, toLcm(scans[e.index]));
      ++result.scans;
    }
    for (auto& m : out.take()) {
      ++result.messages;
      sink(m);
    }
  }
  result.slip_events = static_cast<int>(car.slips().size());
  result.duration_s = rig.sim.duration_s;
  result.path_length_m = car.distanceAt(rig.sim.duration_s);
  return result;
}

}  // namespace sweepmap
