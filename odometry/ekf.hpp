// Planar EKF fusing wheel odometry and a gyro (Miao 2022 Eq. 6-10, extended):
//  - state s = [x, y, theta, v, w, b_g]: pose in the world, forward speed, turn rate, gyro bias;
//    a constant-velocity model predicts it (random-walk acceleration, turn acceleration, bias);
//  - wheel speeds measure (v, w); the gyro measures w + b_g, so its bias is estimated;
//  - the IMU's own yaw (HI219: static error, white noise), relative to its value at the
//    filter's first yaw reading, measures theta (optional: yaw_sigma_rad > 0): it stops
//    the heading drift that gyro noise and an imperfect bias estimate would integrate;
//  - every measurement is gated by its Mahalanobis distance: a slipping wheel disagrees
//    with the gyro about w and is rejected (counted), not fused. A wheel reading given with
//    its interval is first checked against the gyro over that same interval: the wheels' w
//    is the interval's mean, so is the gyro's (less its bias), whatever the phase of the two
//    devices' samples. (The state's w alone would not do: between gyro samples the model's
//    turn acceleration lets it spread by sqrt(turn_accel_psd * 5 ms) = 0.07 rad/s, enough to
//    let a slip through whenever the wheel reading falls just before a gyro sample rather
//    than just after one.) A gyro sample arriving after a wheel reading whose interval holds
//    it re-applies that reading, so the result does not depend on the arrival order;
//  - measurements are applied in timestamp order: one that arrives late is inserted into a
//    short history and everything after it is re-applied, so the estimate equals the one from
//    ordered input; older than the history -> dropped and counted;
//  - non-finite or absurd input is rejected and counted; the state never becomes NaN, and
//    `trusted()` says when the covariance has grown past use (e.g. wheels alone for long).
// 2D mode is explicit: this filter estimates the planar pose only (z, roll, pitch = 0).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <string>
#include <utility>

#include "odometry/wheel_odometry.hpp"

namespace sweepmap {

struct EkfConfig {
  double wheel_distance_m = 0.2;
  double wheel_speed_sigma_fraction = 0.01;  // encoder speed accuracy (1 %)
  double wheel_speed_sigma_min_m_s = 0.002;  // floor near standstill
  double gyro_sigma_rad_s = 0.005;           // gyro white noise
  double accel_psd = 0.5;                    // (m/s^2)^2/Hz, random-walk acceleration
  double turn_accel_psd = 1.0;               // (rad/s^2)^2/Hz
  double bias_psd = 1e-7;                    // (rad/s)^2/s, gyro bias random walk
  double initial_bias_rad_s = 0.0;  // the gyro bias the filter starts from (then estimates)
  double initial_bias_sigma_rad_s = 0.02;
  double gate_chi2_wheels = 13.82;  // 2 dof, p = 0.999
  double gate_chi2_gyro = 10.83;    // 1 dof, p = 0.999
  double yaw_sigma_rad = 0.0;       // IMU yaw noise; 0: yaw not fused
  double gate_chi2_yaw = 10.83;     // 1 dof, p = 0.999
  double history_s = 1.0;           // late measurements within this are re-ordered
  double max_speed_m_s = 5.0;       // beyond: absurd input
  double max_turn_rate_rad_s = 20.0;
  double trusted_theta_sigma_rad = 0.2;  // beyond: not trusted
  // After an input is refused (invalid, or stamped off its stream), poses are not trusted
  // (and the odometry DEGRADED) until good input has covered this much message time.
  double refused_input_window_s = 2.0;
};

using EkfState = Eigen::Matrix<double, 6, 1>;
using EkfCov = Eigen::Matrix<double, 6, 6>;

class OdometryEkf {
 public:
  enum Index { kX = 0, kY, kTheta, kV, kW, kBias };

  explicit OdometryEkf(const EkfConfig& config, int64_t start_utime = 0);

  // Each returns false when the input was rejected (bad, gated out, or too old).
  // Wheels: the mean speeds over an interval of interval_us centred on utime (0: unknown,
  // then only the Mahalanobis gate applies), from encoder counts of tick_m each (0: not
  // counted): a speed from counts is off by up to a count at either end of the interval, so
  // its variance gains tick_m^2 / (6 interval^2) over the configured speed noise.
  bool addWheels(int64_t utime, double v_left_m_s, double v_right_m_s, int64_t interval_us = 0,
                 double tick_m = 0.0);
  bool addGyro(int64_t utime, double w_rad_s);
  // The IMU's yaw; the first one fused sets the offset between its frame and the world.
  bool addYaw(int64_t utime, double yaw_rad);

  const EkfState& state() const { return state_; }
  const EkfCov& covariance() const { return cov_; }
  int64_t utime() const { return utime_; }
  Pose2 pose() const { return {state_[kX], state_[kY], state_[kTheta]}; }
  bool trusted() const;

  struct Counters {
    int64_t wheels = 0, gyro = 0, yaw = 0;  // fused
    int64_t gated_wheels = 0, gated_gyro = 0, gated_yaw = 0;
    int64_t invalid = 0;    // non-finite or absurd
    int64_t reordered = 0;  // late, re-applied in order
    int64_t too_old = 0;    // older than the history
  };
  const Counters& counters() const { return counters_; }

 private:
  enum class Kind { kGyro, kYaw, kWheels };  // application order at equal times
  struct Measurement {
    int64_t utime;
    Kind kind;
    double a, b;              // wheels: v_left, v_right; gyro: w, unused; yaw: yaw, unused
    int64_t interval_us = 0;  // wheels: the interval the speeds are the means of
    double tick_m = 0.0;      // wheels: the distance of one encoder count
  };
  struct Snapshot {
    Measurement m;
    bool accepted;
    EkfState state;  // after the measurement
    EkfCov cov;
    int64_t utime;
  };

  bool add(const Measurement& m);
  bool apply(const Measurement& m);  // predict to m.utime, update; false if gated out
  // The wheels' turn rate disagrees with the gyro's mean over the same interval; *d: the
  // wheels' less the gyro's.
  bool slipsAgainstGyro(const Measurement& m, double w_wheels, double var_w_wheels,
                        double* d) const;
  // The same over the wheel readings of the last kSlipWindowS (this one's and those before it
  // in the history): a slip too small to stand out in one reading stands out over several.
  bool slipsOverWindow(const Measurement& m, double* d) const;
  // A wheel reading's turn rate (w_rad_s) and forward speed, their covariance in R.
  BodyTwist wheelTwist(const Measurement& m, Eigen::Matrix2d* R) const;
  double wheelSpeedSigma(const Measurement& m, double v) const;
  // After a slip: the wheel that did not slip (the left if the wheels turned the body more to
  // the left than the gyro saw, i.e. the right one ran fast) measures v -+ w T / 2.
  void applyGoodWheel(const Measurement& m, double d);
  void insertGyro(int64_t utime, double w);
  static bool holds(const Measurement& wheels, int64_t utime);  // utime within its interval
  void predict(int64_t utime);
  bool update(const Eigen::VectorXd& innovation, const Eigen::MatrixXd& H, const Eigen::MatrixXd& R,
              double gate);

  EkfConfig config_;
  EkfState state_ = EkfState::Zero();
  EkfCov cov_ = EkfCov::Zero();
  int64_t utime_;
  EkfState base_state_;  // state before the oldest snapshot
  EkfCov base_cov_;
  int64_t base_utime_;
  std::deque<Snapshot> history_;
  std::deque<std::pair<int64_t, double>> gyro_;  // valid gyro samples (utime, w), time order
  int64_t max_interval_us_ = 0;                  // longest wheel interval seen
  bool have_yaw_offset_ = false;
  double yaw_offset_ = 0.0;  // IMU yaw minus theta at the first yaw reading
  Counters counters_;
};

}  // namespace sweepmap
