#include "odometry/odometry_config.hpp"

namespace sweepmap {

void OdometryConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "wheel_radius_m", &wheel_radius_m, "m",
        "wheel radius (the left wheel's when they differ)");
  s.add(p + "wheel_radius_right_m", &wheel_radius_right_m, "m",
        "the right wheel's radius when it differs from the left's (sweepmap calib rig measures "
        "both); 0: wheel_radius_m");
  s.add(p + "ticks_per_revolution", &ticks_per_revolution, "", "encoder counts per wheel turn");
  s.add(p + "use_imu", &use_imu, "", "fuse the IMU gyro (false: wheels alone)");
  s.add(p + "wheel_distance_m", &ekf.wheel_distance_m, "m", "distance between the wheels");
  s.add(p + "wheel_speed_sigma_fraction", &ekf.wheel_speed_sigma_fraction, "",
        "wheel speed noise as a fraction of speed");
  s.add(p + "wheel_speed_sigma_min_m_s", &ekf.wheel_speed_sigma_min_m_s, "m/s",
        "wheel speed noise floor");
  s.add(p + "gyro_sigma_rad_s", &ekf.gyro_sigma_rad_s, "rad/s", "gyro white noise");
  s.add(p + "accel_psd", &ekf.accel_psd, "(m/s^2)^2/Hz", "random-walk acceleration");
  s.add(p + "turn_accel_psd", &ekf.turn_accel_psd, "(rad/s^2)^2/Hz",
        "random-walk turn acceleration");
  s.add(p + "bias_psd", &ekf.bias_psd, "(rad/s)^2/s", "gyro bias random walk");
  s.add(p + "gyro_bias_rad_s", &ekf.initial_bias_rad_s, "rad/s",
        "the gyro's z bias the EKF starts from; it goes on estimating it (sweepmap calib rig "
        "measures it)");
  s.add(p + "initial_bias_sigma_rad_s", &ekf.initial_bias_sigma_rad_s, "rad/s",
        "prior on the gyro bias");
  s.add(p + "gate_chi2_wheels", &ekf.gate_chi2_wheels, "", "Mahalanobis gate, wheels (2 dof)");
  s.add(p + "gate_chi2_gyro", &ekf.gate_chi2_gyro, "", "Mahalanobis gate, gyro (1 dof)");
  s.add(p + "yaw_sigma_rad", &ekf.yaw_sigma_rad, "rad",
        "noise of the IMU's own yaw, fused relative to its first reading (0: not fused; a 6-axis "
        "IMU whose yaw drifts needs 0 or a large value)");
  s.add(p + "gate_chi2_yaw", &ekf.gate_chi2_yaw, "", "Mahalanobis gate, IMU yaw (1 dof)");
  s.add(p + "history_s", &ekf.history_s, "s", "late messages within this are re-ordered");
  s.add(p + "max_speed_m_s", &ekf.max_speed_m_s, "m/s", "faster wheel speeds are absurd");
  s.add(p + "max_turn_rate_rad_s", &ekf.max_turn_rate_rad_s, "rad/s", "faster rates are absurd");
  s.add(p + "trusted_theta_sigma_rad", &ekf.trusted_theta_sigma_rad, "rad",
        "heading sigma beyond which the pose is not trusted (and the status DEGRADED)");
  s.add(p + "refused_input_window_s", &ekf.refused_input_window_s, "s",
        "after a refused IMU or WHEEL_TICKS message (invalid, or stamped off its stream), poses "
        "are not trusted and the status is DEGRADED until good input has covered this much "
        "message time");
}

}  // namespace sweepmap
