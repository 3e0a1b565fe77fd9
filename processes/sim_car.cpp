#include "processes/sim_car.hpp"

#include <cmath>
#include <filesystem>

#include "processes/channels.hpp"
#include "processes/sim_setup.hpp"

namespace sweepmap {

void prepareSimMobileConfig(const std::string& rig_path, MobileLidarConfig* rig) {
  if (!rig->sim.path_file.empty() && std::filesystem::path(rig->sim.path_file).is_relative()) {
    rig->sim.path_file =
        (std::filesystem::path(rig_path).parent_path() / rig->sim.path_file).string();
  }
  rig->sim.validate(rig_path);
}

std::unique_ptr<SimMobile> makeSimCar(const MobileLidarConfig& rig, const Scene& scene,
                                      uint64_t seed, int64_t start_utime) {
  const MobileLidarConfig::Build built = rig.build();
  WheelGeometry wheels;
  wheels.radius_m = built.wheel_radius_m;
  wheels.radius_right_m = built.wheel_radius_right_m;
  wheels.ticks_per_revolution = rig.odometry.ticks_per_revolution;
  wheels.wheel_distance_m = built.wheel_distance_m;
  const LidarMounting nominal = rig.mounting.toMounting();
  return std::make_unique<SimMobile>(rig.sim, wheels, nominal.nominal_rpy_rad, built.t_BL_m, scene,
                                     seed, start_utime);
}

truth_mounting_t truthMountingMessage(const MobileLidarConfig& rig, const SceneConfig& scene,
                                      const SimMobile& car, int64_t utime) {
  const LidarMounting nominal = rig.mounting.toMounting();
  truth_mounting_t m{};
  m.utime = utime;
  m.gamma_true_rad = rig.sim.gamma_true_rad;
  m.beta_true_rad = rig.sim.beta_true_rad;
  m.alpha_true_rad = rig.sim.alpha_true_rad;
  const Eigen::Isometry3d W = car.T_room_world();
  for (int k = 0; k < 3; ++k) {
    m.nominal_rpy_rad[k] = nominal.nominal_rpy_rad[k];
    m.t_BL_m[k] = car.trueT_BL().translation()[k];  // the true centre (lever arm error)
  }
  m.world_in_room[0] = W.translation().x();
  m.world_in_room[1] = W.translation().y();
  m.world_in_room[2] = std::atan2(W.linear()(1, 0), W.linear()(0, 0));
  m.room_size_m[0] = scene.room_length_m;
  m.room_size_m[1] = scene.room_width_m;
  m.room_size_m[2] = scene.room_height_m;
  m.scene = scene.name;
  return m;
}

truth_mobile_rig_t truthMobileRigMessage(const MobileLidarConfig& rig, const SimMobile& car,
                                         int64_t utime) {
  truth_mobile_rig_t m{};
  m.utime = utime;
  const SimMobileConfig& c = car.config();
  m.wheel_radius_left_m = car.nominalWheels().radiusOf(false, c);
  m.wheel_radius_right_m = car.nominalWheels().radiusOf(true, c);
  m.wheel_distance_m = car.trueWheelDistance();
  const MobileLidarConfig::Build built = rig.build();
  m.nominal_wheel_radius_m = built.wheel_radius_m;
  m.nominal_wheel_distance_m = built.wheel_distance_m;
  for (int k = 0; k < 3; ++k) {
    m.t_BL_true_m[k] = car.trueT_BL().translation()[k];
    m.t_BL_nominal_m[k] = built.t_BL_m[k];
  }
  m.lidar_time_offset_s = c.lidar_time_offset_ms * 1e-3;
  m.gyro_bias_z_rad_s = c.gyro_bias_z_rad_s;
  setArtefactTruth(c, &m);
  return m;
}

pose2d_t truthPoseMessage(const TruthPose& t) {
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

SimCarTruthNode::SimCarTruthNode(const MobileLidarConfig& rig, const SceneConfig& scene,
                                 const SimMobile* car)
    : Node("sim_truth"), rig_(rig), scene_(scene), car_(car), truth_(*car) {}

void SimCarTruthNode::advance(int64_t now_utime, Outbox& out) {
  if (now_utime >= next_mounting_utime_) {
    out.publish(channels::kTruthMounting, now_utime,
                truthMountingMessage(rig_, scene_, *car_, now_utime));
    out.publish(channels::kTruthMobileRig, now_utime,
                truthMobileRigMessage(rig_, *car_, now_utime));
    next_mounting_utime_ = now_utime + 1000000;
  }
  for (const TruthPose& t : truth_.poll(now_utime)) {
    out.publish(channels::kTruthPose, now_utime, truthPoseMessage(t));
  }
}

}  // namespace sweepmap
