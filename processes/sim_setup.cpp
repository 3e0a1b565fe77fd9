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

truth_rig_errors_t makeTruthRigErrors(const SimRigConfig& sim, int64_t utime) {
  truth_rig_errors_t m{};
  m.utime = utime;
  m.scan_plane_tilt_rad = sim.scan_plane_tilt_deg * M_PI / 180.0;
  m.mirror_offset_rad = sim.mirror_offset_deg * M_PI / 180.0;
  m.plate_thickness_m = sim.plate_thickness_mm * 1e-3;
  setArtefactTruth(sim, &m);
  return m;
}

truth_profile_rig_t makeTruthProfileRig(const SimProfileConfig& sim, int32_t sweep_id,
                                        int64_t utime, const PlatePose* plate) {
  const ProfileGeometry g = sim.trueGeometry();
  truth_profile_rig_t t{};
  t.utime = utime;
  t.sweep_id = sweep_id;
  t.offset_m_mm = g.m_mm;
  t.offset_n_mm = g.n_mm;
  t.laser_tilt_rad = g.laser_tilt_rad;
  t.encoder_zero_rad = g.encoder_zero_rad;
  t.range_noise_sigma_mm = sim.range_noise_sigma_mm;
  t.encoder_noise_counts = sim.encoder_noise_counts;
  t.mixed_pixel_probability = sim.mixed_pixel_probability;
  t.dropout_glancing_probability = sim.dropout_glancing_probability;
  t.dropout_spot_probability = sim.dropout_spot_probability;
  t.scene = sim.scene;
  t.has_plane = plate != nullptr;
  if (plate) {
    for (int i = 0; i < 3; ++i) t.plane_normal[i] = plate->normal[i];
    t.plane_distance_mm = plate->distance();
  }
  return t;
}

truth_test_piece_t makeTruthTestPiece(const TestPieceConfig& c, const ProfileScene::Frame& f,
                                      int32_t sweep_id, int64_t utime) {
  truth_test_piece_t t{};
  t.utime = utime;
  t.sweep_id = sweep_id;
  for (int i = 0; i < 3; ++i) {
    t.origin[i] = f.origin[i];
    t.u_axis[i] = f.u[i];
    t.v_axis[i] = f.v[i];
    t.w_axis[i] = f.w[i];
  }
  t.block_length_mm = c.block_length_mm;
  t.block_width_mm = c.block_width_mm;
  t.spacing_mm = c.spacing_mm;
  t.left_diameter_mm = c.left_diameter_mm;
  t.left_depth_mm = c.left_depth_mm;
  t.right_diameter_mm = c.right_diameter_mm;
  t.right_depth_mm = c.right_depth_mm;
  t.rect_length_mm = c.rect_length_mm;
  t.rect_width_mm = c.rect_width_mm;
  t.rect_depth_mm = c.rect_depth_mm;
  return t;
}

}  // namespace sweepmap
