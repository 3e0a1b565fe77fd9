#include "odometry/ekf.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <vector>

namespace sweepmap {
namespace {

// The slip test's longer window: a tenth of a wheel's speed (the least slip a real tyre shows)
// at 0.2 m/s is 0.1 rad/s of turn rate, 4 sigma of one 20 ms reading, 12 sigma over 0.2 s.
constexpr double kSlipWindowS = 0.2;

}  // namespace

OdometryEkf::OdometryEkf(const EkfConfig& config, int64_t start_utime)
    : config_(config), utime_(start_utime) {
  cov_.diagonal() << 0.0, 0.0, 0.0, 1.0, 1.0,
      config.initial_bias_sigma_rad_s * config.initial_bias_sigma_rad_s;
  state_(kBias) = config.initial_bias_rad_s;
  base_state_ = state_;
  base_cov_ = cov_;
  base_utime_ = utime_;
}

bool OdometryEkf::trusted() const {
  return state_.allFinite() && cov_.allFinite() &&
         cov_(kTheta, kTheta) <= config_.trusted_theta_sigma_rad * config_.trusted_theta_sigma_rad;
}

bool OdometryEkf::addWheels(int64_t utime, double v_left, double v_right, int64_t interval_us,
                            double tick_m) {
  if (!std::isfinite(v_left) || !std::isfinite(v_right) ||
      std::abs(v_left) > config_.max_speed_m_s || std::abs(v_right) > config_.max_speed_m_s) {
    ++counters_.invalid;
    return false;
  }
  interval_us = std::max<int64_t>(0, interval_us);
  max_interval_us_ = std::max(max_interval_us_, interval_us);
  return add({utime, Kind::kWheels, v_left, v_right, interval_us,
              std::isfinite(tick_m) ? std::max(0.0, tick_m) : 0.0});
}

bool OdometryEkf::addGyro(int64_t utime, double w) {
  if (!std::isfinite(w) || std::abs(w) > config_.max_turn_rate_rad_s) {
    ++counters_.invalid;
    return false;
  }
  return add({utime, Kind::kGyro, w, 0.0});
}

bool OdometryEkf::addYaw(int64_t utime, double yaw) {
  if (!(config_.yaw_sigma_rad > 0.0)) return false;
  if (!std::isfinite(yaw) || std::abs(yaw) > 100.0) {
    ++counters_.invalid;
    return false;
  }
  return add({utime, Kind::kYaw, yaw, 0.0});
}

bool OdometryEkf::add(const Measurement& m) {
  if (m.utime < base_utime_) {
    ++counters_.too_old;
    return false;
  }
  const auto count = [&](const Snapshot& s, int sign) {
    int64_t& fused = s.m.kind == Kind::kWheels ? counters_.wheels
                     : s.m.kind == Kind::kGyro ? counters_.gyro
                                               : counters_.yaw;
    int64_t& gated = s.m.kind == Kind::kWheels ? counters_.gated_wheels
                     : s.m.kind == Kind::kGyro ? counters_.gated_gyro
                                               : counters_.gated_yaw;
    (s.accepted ? fused : gated) += sign;
  };
  // Measurements apply in (time, kind) order, wheels after gyro and yaw at equal times,
  // yaw after gyro, so the result does not depend on arrival order.
  const auto after = [](const Measurement& a, const Measurement& b) {
    return a.utime > b.utime ||
           (a.utime == b.utime && static_cast<int>(a.kind) > static_cast<int>(b.kind));
  };
  // Re-applied from the first of: the measurements after this one (late arrival) and, for a
  // gyro sample, the wheel readings whose interval holds it (their slip check uses it).
  size_t keep = history_.size();
  while (keep > 0 && after(history_[keep - 1].m, m)) --keep;
  const bool late = keep < history_.size();
  if (m.kind == Kind::kGyro) {
    insertGyro(m.utime, m.a);
    for (size_t i = keep; i > 0 && history_[i - 1].m.utime + max_interval_us_ / 2 >= m.utime; --i) {
      if (holds(history_[i - 1].m, m.utime)) keep = i - 1;
    }
  }
  std::vector<Snapshot> later(history_.begin() + static_cast<std::ptrdiff_t>(keep), history_.end());
  for (const Snapshot& s : later) count(s, -1);
  history_.erase(history_.begin() + static_cast<std::ptrdiff_t>(keep), history_.end());
  if (late) ++counters_.reordered;
  if (!later.empty()) {
    if (history_.empty()) {
      state_ = base_state_;
      cov_ = base_cov_;
      utime_ = base_utime_;
    } else {
      state_ = history_.back().state;
      cov_ = history_.back().cov;
      utime_ = history_.back().utime;
    }
  }
  const auto applyAndKeep = [&](const Measurement& x) {
    Snapshot s{x, apply(x), state_, cov_, utime_};
    count(s, +1);
    history_.push_back(s);
    return s.accepted;
  };
  bool accepted = false, applied = false;
  for (const Snapshot& s : later) {
    if (!applied && after(s.m, m)) {
      accepted = applyAndKeep(m);
      applied = true;
    }
    applyAndKeep(s.m);
  }
  if (!applied) accepted = applyAndKeep(m);
  // Forget what is older than the history window.
  const int64_t keep_us = static_cast<int64_t>(config_.history_s * 1e6);
  while (!history_.empty() && history_.front().m.utime < utime_ - keep_us) {
    base_state_ = history_.front().state;
    base_cov_ = history_.front().cov;
    base_utime_ = history_.front().utime;
    history_.pop_front();
  }
  // Gyro samples are kept as long as a wheel reading in the history may span them.
  while (!gyro_.empty() && gyro_.front().first < base_utime_ - max_interval_us_) gyro_.pop_front();
  return accepted;
}

void OdometryEkf::insertGyro(int64_t utime, double w) {
  auto it = gyro_.end();
  while (it != gyro_.begin() && std::prev(it)->first > utime) --it;
  gyro_.insert(it, {utime, w});
}

bool OdometryEkf::holds(const Measurement& wheels, int64_t utime) {
  if (wheels.kind != Kind::kWheels || wheels.interval_us <= 0) return false;
  const int64_t lo = wheels.utime - wheels.interval_us / 2;
  return utime >= lo && utime <= lo + wheels.interval_us;
}

bool OdometryEkf::slipsAgainstGyro(const Measurement& m, double w_wheels, double var_w_wheels,
                                   double* d) const {
  if (m.interval_us <= 0) return false;
  double sum = 0.0;
  int n = 0;
  for (auto it = gyro_.rbegin(); it != gyro_.rend() && it->first >= m.utime - m.interval_us; ++it) {
    if (holds(m, it->first)) {
      sum += it->second;
      ++n;
    }
  }
  if (n == 0) return false;  // no gyro over the interval (IMU off or silent): the gate alone
  // Both are the interval's mean turn rate: the gyro's less its bias estimate.
  const double w_gyro = sum / n - state_[kBias];
  const double gyro_var = config_.gyro_sigma_rad_s * config_.gyro_sigma_rad_s / n;
  const double var = var_w_wheels + gyro_var + cov_(kBias, kBias);
  *d = w_wheels - w_gyro;
  return *d * *d > config_.gate_chi2_gyro * var;
}

bool OdometryEkf::slipsOverWindow(const Measurement& m, double* d) const {
  if (m.interval_us <= 0) return false;
  const int64_t from = m.utime - static_cast<int64_t>(kSlipWindowS * 1e6);
  double turned = 0.0, var = 0.0, span = 0.0, gyro = 0.0;
  int n = 0;
  const auto take = [&](const Measurement& w) {
    Eigen::Matrix2d R;
    const double dt = 1e-6 * static_cast<double>(w.interval_us);
    turned += wheelTwist(w, &R).w_rad_s * dt;
    var += R(1, 1) * dt * dt;
    span += dt;
    for (auto it = gyro_.rbegin(); it != gyro_.rend() && it->first >= w.utime - w.interval_us;
         ++it) {
      if (holds(w, it->first)) {
        gyro += it->second;
        ++n;
      }
    }
  };
  take(m);
  int readings = 1;
  for (auto it = history_.rbegin(); it != history_.rend() && it->m.utime >= from; ++it) {
    if (it->m.kind != Kind::kWheels || it->m.interval_us <= 0 || it->m.utime >= m.utime) continue;
    take(it->m);
    ++readings;
  }
  if (n == 0 || readings < 2) return false;
  const double gyro_var = config_.gyro_sigma_rad_s * config_.gyro_sigma_rad_s / n;
  *d = turned / span - (gyro / n - state_[kBias]);
  return *d * *d > config_.gate_chi2_gyro * (var / (span * span) + gyro_var + cov_(kBias, kBias));
}

double OdometryEkf::wheelSpeedSigma(const Measurement& m, double v) const {
  // Quantisation: the counts at both ends of the interval are each off by U(-1/2, 1/2).
  const double quantum =
      m.interval_us > 0 ? m.tick_m / (1e-6 * double(m.interval_us) * std::sqrt(6.0)) : 0.0;
  return std::hypot(
      std::max(config_.wheel_speed_sigma_min_m_s, config_.wheel_speed_sigma_fraction * std::abs(v)),
      quantum);
}

BodyTwist OdometryEkf::wheelTwist(const Measurement& m, Eigen::Matrix2d* R) const {
  const double sl = wheelSpeedSigma(m, m.a), sr = wheelSpeedSigma(m, m.b);
  const double wd = config_.wheel_distance_m;
  // (v, w) = A (v_l, v_r): R = A diag(sl^2, sr^2) A^T
  *R << 0.25 * (sl * sl + sr * sr), 0.5 * (sr * sr - sl * sl) / wd, 0.5 * (sr * sr - sl * sl) / wd,
      (sl * sl + sr * sr) / (wd * wd);
  return twistFromWheels(m.a, m.b, wd);
}

void OdometryEkf::applyGoodWheel(const Measurement& m, double d) {
  const bool left = d > 0;  // the right wheel ran fast
  const double v = left ? m.a : m.b, half = 0.5 * config_.wheel_distance_m;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(1, 6);
  H(0, kV) = 1.0;
  H(0, kW) = left ? -half : half;
  Eigen::VectorXd y(1);
  y[0] = v - (state_[kV] + H(0, kW) * state_[kW]);
  Eigen::MatrixXd R(1, 1);
  R(0, 0) = wheelSpeedSigma(m, v) * wheelSpeedSigma(m, v);
  update(y, H, R, config_.gate_chi2_gyro);
}

void OdometryEkf::predict(int64_t utime) {
  const double dt = 1e-6 * static_cast<double>(utime - utime_);
  if (dt <= 0.0) return;
  // Heading at the middle of the step: second-order accurate on arcs, so the result does
  // not depend on the measurement rate.
  const double v = state_[kV], w = state_[kW];
  const double th = state_[kTheta] + 0.5 * w * dt;
  const double c = std::cos(th), s = std::sin(th);
  EkfCov F = EkfCov::Identity();
  F(kX, kTheta) = -v * dt * s;
  F(kX, kV) = dt * c;
  F(kY, kTheta) = v * dt * c;
  F(kY, kV) = dt * s;
  F(kX, kW) = -0.5 * v * dt * dt * s;
  F(kY, kW) = 0.5 * v * dt * dt * c;
  F(kTheta, kW) = dt;
  state_[kX] += v * dt * c;
  state_[kY] += v * dt * s;
  state_[kTheta] += w * dt;
  EkfCov Q = EkfCov::Zero();
  const double dt3 = dt * dt * dt / 3.0;
  Q(kX, kX) = Q(kY, kY) = config_.accel_psd * dt3;
  Q(kTheta, kTheta) = config_.turn_accel_psd * dt3;
  Q(kV, kV) = config_.accel_psd * dt;
  Q(kW, kW) = config_.turn_accel_psd * dt;
  Q(kBias, kBias) = config_.bias_psd * dt;
  cov_ = F * cov_ * F.transpose() + Q;
  utime_ = utime;
}

bool OdometryEkf::update(const Eigen::VectorXd& y, const Eigen::MatrixXd& H,
                         const Eigen::MatrixXd& R, double gate) {
  const Eigen::MatrixXd S = H * cov_ * H.transpose() + R;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(S);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  const double d2 = y.dot(ldlt.solve(y));
  if (!std::isfinite(d2) || d2 > gate) return false;
  const Eigen::MatrixXd K =
      cov_ * H.transpose() * ldlt.solve(Eigen::MatrixXd::Identity(S.rows(), S.cols()));
  const EkfState next = state_ + K * y;
  const EkfCov I_KH = EkfCov::Identity() - K * H;
  const EkfCov next_cov = I_KH * cov_ * I_KH.transpose() + K * R * K.transpose();  // Joseph form
  if (!next.allFinite() || !next_cov.allFinite()) return false;
  state_ = next;
  cov_ = 0.5 * (next_cov + next_cov.transpose());
  return true;
}

bool OdometryEkf::apply(const Measurement& m) {
  predict(m.utime);
  if (m.kind == Kind::kWheels) {
    Eigen::Matrix2d R;
    const BodyTwist t = wheelTwist(m, &R);
    // A slip refuses the pair (counted as gated); the wheel that did not slip still measures
    // the speed with the gyro's turn rate, so the distance does not coast on the last speed.
    double d = 0.0;
    if (slipsAgainstGyro(m, t.w_rad_s, R(1, 1), &d) || slipsOverWindow(m, &d)) {
      applyGoodWheel(m, d);
      return false;
    }
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, 6);
    H(0, kV) = 1.0;
    H(1, kW) = 1.0;
    Eigen::Vector2d y(t.v_m_s - state_[kV], t.w_rad_s - state_[kW]);
    return update(y, H, R, config_.gate_chi2_wheels);
  }
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(1, 6);
  Eigen::VectorXd y(1);
  Eigen::MatrixXd R(1, 1);
  if (m.kind == Kind::kYaw) {
    if (!have_yaw_offset_) {  // the first reading ties the IMU's yaw to the world frame
      yaw_offset_ = m.a - state_[kTheta];
      have_yaw_offset_ = true;
      return true;
    }
    H(0, kTheta) = 1.0;
    y[0] = std::remainder(m.a - yaw_offset_ - state_[kTheta], 2.0 * M_PI);
    R(0, 0) = config_.yaw_sigma_rad * config_.yaw_sigma_rad;
    return update(y, H, R, config_.gate_chi2_yaw);
  }
  H(0, kW) = 1.0;
  H(0, kBias) = 1.0;
  y[0] = m.a - (state_[kW] + state_[kBias]);
  R(0, 0) = config_.gyro_sigma_rad_s * config_.gyro_sigma_rad_s;
  return update(y, H, R, config_.gate_chi2_gyro);
}

}  // namespace sweepmap
