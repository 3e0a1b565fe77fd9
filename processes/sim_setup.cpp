#include "processes/sim_setup.hpp"

#include <cmath>

namespace sweepmap {

truth_rig_t makeTruthRig(const RotatingLidarConfig& rig, const SceneConfig& scene_config,
                         const Scene& scene, int64_t utime) {
  truth_rig_t m;
  m.utime = utime;
  const Eigen::Isometry3d T = scene.T_room_rig();
  for (int i = 0; i < 3; ++i) m.position_m[i] = T.translation()[i];
  const Eigen::Matrix3d R = T.rotation();
  m.yaw_rad = std::atan2(R(1, 0), R(0, 0));
  m.alpha_true_rad = rig.sim.alpha_true_deg * M_PI / 180.0;
  m.lidar_offset_x_m = rig.sim.lidar_offset_x_mm * 1e-3;
  m.range_noise_sigma_m = rig.sim.range_noise_sigma_mm * 1e-3;
  m.scene = scene_config.name;
  return m;
}

}  // namespace sweepmap
