// The assembler of rig C (Zhao 2021): every PROFILE placed in frame O_r by the generalised
// Eq. 7 (core/profile_geometry.hpp: profilePointsInRigFrameM) at its latched encoder angle
// with the rig's geometry, and published as one self-describing chunk on SWEEP_CLOUD (frame
// "O_r", utime = the exposure, sweep_id = the turntable's sweep, sensor origin = the
// sensor's origin at that angle, for the mapper's ray casting). Each profile stands alone,
// so the output depends only on the PROFILE messages: live and replayed clouds are equal.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "core/profile.hpp"
#include "core/profile_geometry.hpp"
#include "processes/node.hpp"

namespace sweepmap {

class ProfileAssemblerNode : public Node {
 public:
  explicit ProfileAssemblerNode(const ProfileGeometry& geometry);
  std::vector<std::string> subscriptions() const override;
  const ProfileGeometry& geometry() const { return geometry_; }

  // Offline tools: every assembled profile and its points [m, O_r].
  using Observer = std::function<void(const Profile&, const std::vector<Eigen::Vector3f>&)>;
  void setObserver(Observer o) { observer_ = std::move(o); }

 protected:
  void handle(const Message& msg, Outbox& out) override;

 private:
  ProfileGeometry geometry_;
  bool has_last_ = false;
  int64_t last_utime_ = 0;
  Observer observer_;
};

}  // namespace sweepmap
