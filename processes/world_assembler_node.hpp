// The assembler in rig-B mode: every lidar scan goes to the world frame with the pose
// interpolated at each ray's own time (deskewing) and the mounting T_BL (Miao 2022
// Eq. 11-14), and is published as one self-describing chunk on SWEEP_CLOUD (frame
// "world", sensor origin = the lidar's position mid-scan) for the mapper. Scans are put on the
// odometry's clock first (the rig's lidar.time_offset_s), their chunks stamped so. A scan waits
// until the pose stream has passed its last ray (or max_pose_wait_s); rays without a
// pose are dropped and counted.
#pragma once

#include <deque>
#include <functional>

#include "calib/world_assembly.hpp"
#include "processes/node.hpp"
#include "rigs/mobile_lidar.hpp"

namespace sweepmap {

class WorldAssemblerNode : public Node {
 public:
  WorldAssemblerNode(const WorldAssemblerConfig& config, const LidarMounting& mounting);
  std::vector<std::string> subscriptions() const override;
  void finish(int64_t now_utime, Outbox& out) override;

  // Offline tools: every assembled scan's world points, their intensities (empty when the
  // lidar measures none, else one per point) and the sensor origin.
  using Observer =
      std::function<void(int64_t utime, const std::vector<Eigen::Vector3f>& points,
                         const std::vector<float>& intensities, const Eigen::Vector3d& origin)>;
  void setObserver(Observer o) { observer_ = std::move(o); }

 protected:
  void handle(const Message& msg, Outbox& out) override;

 private:
  void assembleReady(int64_t now_utime, bool flush, Outbox& out);
  void publishScan(int64_t now_utime, const Scan2D& scan, Outbox& out);

  WorldAssemblerConfig config_;
  Eigen::Isometry3d T_BL_;
  PoseTrack track_;
  std::deque<Scan2D> pending_;
  int64_t next_id_ = 0;
  int64_t last_assembled_utime_ = INT64_MIN;
  Observer observer_;
};

}  // namespace sweepmap
