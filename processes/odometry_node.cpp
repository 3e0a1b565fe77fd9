#include "processes/odometry_node.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/wheel_cmd_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"

namespace sweepmap {

OdometryNode::OdometryNode(const OdometryConfig& config)
    : Node("odometry"), config_(config), ekf_(config.ekf) {}

OdometryNode::OdometryNode(const OdometryConfig& config, ImuDevice* imu, WheelDevice* wheels)
    : OdometryNode(config) {
  imu_device_ = imu;
  wheel_device_ = wheels;
}

std::vector<std::string> OdometryNode::subscriptions() const {
  if (wheel_device_) return {channels::kWheelCmd};
  return {channels::kWheelTicks, channels::kImu};
}

void OdometryNode::handle(const Message& msg, Outbox& out) {
  if (msg.channel == channels::kWheelCmd) {
    wheel_cmd_t c;
    if (!decodeMessage(msg, &c) || !std::isfinite(c.v_m_s) || !std::isfinite(c.w_rad_s) ||
        std::abs(c.v_m_s) > config_.ekf.max_speed_m_s ||
        std::abs(c.w_rad_s) > config_.ekf.max_turn_rate_rad_s) {
      reportError("invalid", "malformed or absurd wheel_cmd_t");
      return;
    }
    if (wheel_device_) wheel_device_->command(msg.utime, c.v_m_s, c.w_rad_s);
    count("wheel_commands");
    return;
  }
  process(msg, out);
}

void OdometryNode::process(const Message& msg, Outbox& out) {
  if (msg.channel == channels::kWheelTicks) {
    if (last_imu_rx_ < 0) last_imu_rx_ = msg.utime;  // the IMU's timeout starts with the wheels
    last_wheels_rx_ = msg.utime;
    onTicks(msg, out);
  } else if (msg.channel == channels::kImu) {
    last_imu_rx_ = msg.utime;
    onImu(msg);
  }
}

void OdometryNode::advance(int64_t now_utime, Outbox& out) {
  if (imu_device_ && wheel_device_) pollDevices(now_utime, out);
  checkImu(now_utime);
}

void OdometryNode::pollDevices(int64_t now_utime, Outbox& out) {
  for (const auto& [device, prefix] :
       {std::pair<DeviceHealth, const char*>{imu_device_->health(), "imu_"},
        std::pair<DeviceHealth, const char*>{wheel_device_->health(), "wheels_"}}) {
    for (const auto& [name, value] : device.counters) setCounter(prefix + name, value);
    for (const std::string& e : device.events) reportEvent(e);
  }
  // Both devices' samples in time order (the IMU's first at equal times), published raw and
  // then processed in that order.
  const std::vector<ImuSample> imu = imu_device_->poll(now_utime);
  const std::vector<WheelTicks> wheels = wheel_device_->poll(now_utime);
  Outbox raw;
  size_t i = 0, w = 0;
  while (i < imu.size() || w < wheels.size()) {
    if (w >= wheels.size() || (i < imu.size() && imu[i].utime <= wheels[w].utime)) {
      raw.publish(channels::kImu, now_utime, toLcm(imu[i++]));
    } else {
      raw.publish(channels::kWheelTicks, now_utime, toLcm(wheels[w++]));
    }
  }
  for (Message& m : raw.take()) {
    out.push(m);
    process(m, out);
  }
}

// The status: DEGRADED while input was refused recently, the IMU is out, or the EKF's covariance
// says its poses are not to be trusted (in that order of precedence); OK otherwise.
void OdometryNode::checkImu(int64_t now_utime) {
  if (config_.use_imu && last_wheels_rx_ >= 0) {
    const bool wheels_alive = now_utime - last_wheels_rx_ <= kImuTimeoutUs;
    const bool imu_silent = now_utime - last_imu_rx_ > kImuTimeoutUs;
    if (wheels_alive && imu_silent && !imu_out_) count("imu_outages");
    if (wheels_alive && imu_silent) imu_out_ = true;
    if (!imu_silent) imu_out_ = false;
  }
  if (ekf_started_ && refusedRecently(latest_stamp_)) {
    setDegraded(refused_channel_ +
                " input refused: poses not trusted until good input has covered " +
                std::to_string(config_.ekf.refused_input_window_s) + " s");
  } else if (imu_out_) {
    setDegraded("no IMU sample for " + std::to_string(kImuTimeoutUs / 1000) +
                " ms: EKF on wheels alone");
  } else if (ekf_started_ && !ekf_.trusted()) {
    setDegraded("EKF heading sigma over odometry.trusted_theta_sigma_rad: poses not trusted");
  } else {
    clearDegraded("IMU and wheels fused, input good: poses trusted");
  }
}

void OdometryNode::onRefused(const Message& msg) {
  if (msg.channel == channels::kImu || msg.channel == channels::kWheelTicks) refused(msg.channel);
}

// Poses are not trusted until good input has covered the window from the latest good stamp.
void OdometryNode::refused(const std::string& channel) {
  count("refused_input");
  refused_channel_ = channel;
  trust_again_from_ =
      latest_stamp_ + static_cast<int64_t>(config_.ekf.refused_input_window_s * 1e6);
}

void OdometryNode::onTicks(const Message& msg, Outbox& out) {
  wheel_ticks_t m;
  if (!decodeMessage(msg, &m)) {
    reportError("invalid", "malformed wheel_ticks_t");
    refused(msg.channel);
    return;
  }
  if (!last_ticks_) {
    latest_stamp_ = std::max(latest_stamp_, m.utime);
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
    refused(msg.channel);
    return;
  }
  const double dt = 1e-6 * static_cast<double>(m.utime - last_ticks_->utime);
  const double per_tick = 2.0 * M_PI * config_.wheel_radius_m / config_.ticks_per_revolution;
  const double per_tick_right =
      2.0 * M_PI * config_.rightWheelRadius() / config_.ticks_per_revolution;
  const double vl = static_cast<double>(m.left_ticks - last_ticks_->left) * per_tick / dt;
  const double vr = static_cast<double>(m.right_ticks - last_ticks_->right) * per_tick_right / dt;
  if (!std::isfinite(vl) || !std::isfinite(vr) || std::abs(vl) > config_.ekf.max_speed_m_s ||
      std::abs(vr) > config_.ekf.max_speed_m_s) {
    reportError("invalid", "absurd wheel speed " + std::to_string(vl) + ", " + std::to_string(vr) +
                               " m/s (ticks jumped?)");
    last_ticks_ = Ticks{m.utime, m.left_ticks, m.right_ticks};
    refused(msg.channel);
    return;
  }
  latest_stamp_ = std::max(latest_stamp_, m.utime);
  // Wheel odometry, Eq. 2-5, with the speeds over the interval just ended.
  last_twist_ = twistFromWheels(vl, vr, config_.ekf.wheel_distance_m);
  odometry_ = integrateOdometry(odometry_, last_twist_, dt);
  // The speeds are the interval's means: they belong to its middle, and the EKF checks them
  // against the gyro over the same interval.
  const int64_t interval = m.utime - last_ticks_->utime;
  const int64_t mid = last_ticks_->utime + interval / 2;
  last_ticks_ = Ticks{m.utime, m.left_ticks, m.right_ticks};
  if (!ekf_.addWheels(mid, vl, vr, interval, per_tick)) count("wheels_rejected");
  publish(m.utime, msg.utime, out);
}

void OdometryNode::onImu(const Message& msg) {
  if (!config_.use_imu) return;
  imu_t m;
  if (!decodeMessage(msg, &m)) {
    reportError("invalid", "malformed imu_t");
    refused(msg.channel);
    return;
  }
  if (!ekf_started_) {
    ekf_ = OdometryEkf(config_.ekf, m.utime);
    ekf_started_ = true;
  }
  latest_stamp_ = std::max(latest_stamp_, m.utime);
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
  e.trusted = trustedAt(e.utime);
  if (!e.trusted) count("untrusted_poses");
  out.publish(channels::kOdometryPose, now, e);
}

}  // namespace sweepmap
