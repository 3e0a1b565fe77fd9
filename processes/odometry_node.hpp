// sweepmap-odometry (rig B): wheel encoder counts and IMU gyro -> planar pose. Publishes
// WHEEL_ODOMETRY (wheels alone, Miao 2022 Eq. 2-5) and ODOMETRY_POSE (the EKF of
// odometry/ekf.hpp) after every accepted wheel reading. Raw input that is non-finite,
// goes back in time or implies absurd rates is rejected and counted; the EKF handles
// late messages itself.
//
// Devices. Given the IMU and the wheel board (real drivers or the simulated car's), the node
// owns them, as the motor process owns the stepper: at each tick it polls both, publishes
// their samples raw (IMU, WHEEL_TICKS) first, merged in time order, and then processes each
// in that same order, so that the live poses equal those of a replay of the recorded log.
// WHEEL_CMD goes to the wheel board. The drivers' counters appear in the status as imu_* and
// wheels_*. Without devices (--from-lcm, replay) it subscribes to IMU and WHEEL_TICKS.
//
// IMU outage: while wheel readings arrive and no IMU sample has come for imu_timeout (a
// disconnected IMU is reconnecting), the status is DEGRADED ("EKF on wheels alone") and the EKF
// goes on from the wheels alone; counted in imu_outages, cleared when samples return.
//
// Refused input: after an IMU or WHEEL_TICKS message is refused (invalid, stamped off its
// stream, absurd), the poses say trusted = false and the status DEGRADED until good input has
// covered ekf.refused_input_window_s of message time (the window is in message time, so live
// and replay agree); so do they while the EKF's covariance says it is not to be trusted
// (heading sigma over ekf.trusted_theta_sigma_rad).
#pragma once

#include <optional>

#include "devices/odometry_devices.hpp"
#include "odometry/ekf.hpp"
#include "odometry/odometry_config.hpp"
#include "processes/node.hpp"

namespace sweepmap {

class OdometryNode : public Node {
 public:
  explicit OdometryNode(const OdometryConfig& config);
  // The node that owns its devices (both non-null).
  OdometryNode(const OdometryConfig& config, ImuDevice* imu, WheelDevice* wheels);
  std::vector<std::string> subscriptions() const override;
  static constexpr int64_t kImuTimeoutUs = 500000;
  const OdometryEkf& ekf() const { return ekf_; }
  const Pose2& wheelOdometry() const { return odometry_; }

 protected:
  void handle(const Message& msg, Outbox& out) override;
  void advance(int64_t now_utime, Outbox& out) override;
  void onRefused(const Message& msg) override;

 private:
  void process(const Message& msg, Outbox& out);
  void pollDevices(int64_t now_utime, Outbox& out);
  void checkImu(int64_t now_utime);
  void refused(const std::string& channel);
  bool refusedRecently(int64_t stamp) const { return stamp < trust_again_from_; }
  bool trustedAt(int64_t stamp) const { return ekf_.trusted() && !refusedRecently(stamp); }
  void onTicks(const Message& msg, Outbox& out);
  void onImu(const Message& msg);
  void publish(int64_t utime, int64_t now, Outbox& out);

  OdometryConfig config_;
  OdometryEkf ekf_;
  Pose2 odometry_;
  BodyTwist last_twist_;
  struct Ticks {
    int64_t utime, left, right;
  };
  std::optional<Ticks> last_ticks_;
  bool ekf_started_ = false;  // the EKF starts at the first message of either kind

  ImuDevice* imu_device_ = nullptr;
  WheelDevice* wheel_device_ = nullptr;
  // Receive times [us] of the latest IMU and wheel messages (-1: none yet).
  int64_t last_imu_rx_ = -1, last_wheels_rx_ = -1;
  bool imu_out_ = false;
  // Refused input: the latest stamp of good input, and the stamp from which poses are trusted
  // again; the channel of the last refusal.
  int64_t latest_stamp_ = 0;
  int64_t trust_again_from_ = 0;
  std::string refused_channel_;
};

}  // namespace sweepmap
