#include "processes/odometry_node.hpp"

#include <cmath>

#include "processes/channels.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"

namespace sweepmap {

OdometryNode::OdometryNode(const OdometryConfig& config)
    : Node("odometry"), config_(config), ekf_(config.ekf) {}

std::vector<std::string> OdometryNode::subscriptions() const {
  return {channels::kWheelTicks, channels::kImu};
}

void OdometryNode::handle(const Message& msg, Outbox& out) {
  if (msg.channel == channels::kWheelTicks) {
    onTicks(msg, out);
  } else if (msg.channel == channels::kImu) {
    onImu(msg);
  }
}

void OdometryNode::onTicks(const Message& msg, Outbox& out) {
  wheel_ticks_t m;
  if (!decodeMessage(msg, &m)) {
    reportError("invalid", "malformed wheel_ticks_t");
    return;
  }
  if (!last_ticks_) {
    last_ticks_ = Ticks{m.utime, m.left_ticks, m.right_ticks};
    if (!ekf_started_) {
      ekf_ = OdometryEkf(config_.ekf, m.utime);
      ekf_started_ = true;
    }
    return;
  }
  if (m.utime <= last_ticks_->utime) {
    reportError("invalid", "wheel ticks at " + std::to_string(m.utime) + " us not after " +
                               std::to_string(last_ticks_->utime) + " us");
    return;
  }
  const double dt = 1e-6 * static_cast<double>(m.utime - last_ticks_->utime);
  const double per_tick = 2.0 * M_PI * config_.wheel_radius_m / config_.ticks_per_revolution;
  const double vl = static_cast<double>(m.left_ticks - last_ticks_->left) * per_tick / dt;
  const double vr = static_cast<double>(m.right_ticks - last_ticks_->right) * per_tick / dt;
  if (!std::isfinite(vl) || !std::isfinite(vr) || std::abs(vl) > config_.ekf.max_speed_m_s ||
      std::abs(vr) > config_.ekf.max_speed_m_s) {
    reportError("invalid", "absurd wheel speed " + std::to_string(vl) + ", " + std::to_string(vr) +
                               " m/s (ticks jumped?)");
    last_ticks_ = Ticks{m.utime, m.left_ticks, m.right_ticks};
    return;
  }
  // Wheel odometry, Eq. 2-5, with the speeds over the interval just ended.
  last_twist_ = twistFromWheels(vl, vr, config_.ekf.wheel_distance_m);
  odometry_ = integrateOdometry(odometry_, last_twist_, dt);
  // The speeds are the interval's means: they belong to its middle.
  const int64_t mid = last_ticks_->utime + (m.utime - last_ticks_->utime) / 2;
  last_ticks_ = Ticks{m.utime, m.left_ticks, m.right_ticks};
  if (!ekf_.addWheels(mid, vl, vr)) count("wheels_rejected");
  publish(m.utime, msg.utime, out);
}

void OdometryNode::onImu(const Message& msg) {
  if (!config_.use_imu) return;
  imu_t m;
  if (!decodeMessage(msg, &m)) {
    reportError("invalid", "malformed imu_t");
    return;
  }
  if (!ekf_started_) {
    ekf_ = OdometryEkf(config_.ekf, m.utime);
    ekf_started_ = true;
  }
  if (!ekf_.addGyro(m.utime, m.gyro_rad_s[2])) count("gyro_rejected");
  if (config_.ekf.yaw_sigma_rad > 0.0 && !ekf_.addYaw(m.utime, m.rpy_rad[2])) count("yaw_rejected");
}

void OdometryNode::publish(int64_t utime, int64_t now, Outbox& out) {
  pose2d_t w{};
  w.utime = utime;
  w.x_m = odometry_.x_m;
  w.y_m = odometry_.y_m;
  w.theta_rad = odometry_.theta_rad;
  w.v_m_s = last_twist_.v_m_s;
  w.w_rad_s = last_twist_.w_rad_s;
  w.trusted = false;  // no covariance for plain odometry
  out.publish(channels::kWheelOdometry, now, w);

  const EkfState& s = ekf_.state();
  pose2d_t e{};
  e.utime = ekf_.utime();
  e.x_m = s[OdometryEkf::kX];
  e.y_m = s[OdometryEkf::kY];
  e.theta_rad = s[OdometryEkf::kTheta];
  e.v_m_s = s[OdometryEkf::kV];
  e.w_rad_s = s[OdometryEkf::kW];
  e.gyro_bias_rad_s = s[OdometryEkf::kBias];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) e.covariance[r * 3 + c] = ekf_.covariance()(r, c);
  }
  e.trusted = ekf_.trusted();
  if (!e.trusted) count("untrusted_poses");
  out.publish(channels::kOdometryPose, now, e);
}

}  // namespace sweepmap
