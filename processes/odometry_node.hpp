// sweepmap-odometry (rig B): wheel encoder counts and IMU gyro -> planar pose. Publishes
// WHEEL_ODOMETRY (wheels alone, Miao 2022 Eq. 2-5) and ODOMETRY_POSE (the EKF of
// odometry/ekf.hpp) after every accepted wheel reading. Raw input that is non-finite,
// goes back in time or implies absurd rates is rejected and counted; the EKF handles
// late messages itself.
#pragma once

#include <optional>

#include "odometry/ekf.hpp"
#include "odometry/odometry_config.hpp"
#include "processes/node.hpp"

namespace sweepmap {

class OdometryNode : public Node {
 public:
  explicit OdometryNode(const OdometryConfig& config);
  std::vector<std::string> subscriptions() const override;
  const OdometryEkf& ekf() const { return ekf_; }
  const Pose2& wheelOdometry() const { return odometry_; }

 protected:
  void handle(const Message& msg, Outbox& out) override;

 private:
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
};

}  // namespace sweepmap
