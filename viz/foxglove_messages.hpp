// sweepmap's LCM messages as Foxglove messages (JSON encoding, the documented JSON schemas of
// @foxglove/schemas, embedded from viz/schemas/): the one conversion that both the live view's
// Foxglove WebSocket server and `sweepmap export mcap` use, so a recording and a live session
// show the same topics.
//
// Topics (derived; the raw LCM channels keep their own names elsewhere):
//   /sweep_cloud   foxglove.PointCloud      each SWEEP_CLOUD chunk, float32 x, y, z [m] in the
//                                           chunk's frame, and float32 intensity (the lidar's
//                                           device units) when the chunk carries intensities
//   /map           foxglove.PointCloud      centres of the mapper's occupied voxels, kept from
//                                           MAP_UPDATE; at most once per second of log time,
//                                           after an update's last chunk, SWEEP_STATUS or
//                                           MAP_STATS (at once on the first update), and
//                                           from finish().
//                                           Until a MAP_UPDATE comes (a log recorded before the
//                                           mapper published it), the voxels a cloud point fell
//                                           in, at the rig's mapper resolution.
//   /pose, /wheel_odometry, /truth_pose
//                  foxglove.PoseInFrame     ODOMETRY_POSE, WHEEL_ODOMETRY, TRUTH_POSE in "world"
//   /tf            foxglove.FrameTransform  the rig's frames: its static ones (mounting, lidar
//                                           offset) with the first message, the moving ones
//                                           from ODOMETRY_POSE (world->body), MOTOR_STATE
//                                           (rig A: O'->L), each cloud's phi_offset (O->O'),
//                                           PROFILE (rig C: O_r->S)
//   /lidar_scan    foxglove.LaserScan       LIDAR_SCAN with evenly spaced rays, frame L
//   /lidar_points  foxglove.PointCloud      LIDAR_SCAN with per-ray angles (nangles > 0):
//                                           LaserScan cannot hold uneven angles, so its points
//                                           (0, r sin a, r cos a) in frame L, with intensity
//   /profile       foxglove.PointCloud      PROFILE (rig C): (0, y, z) [m] in the sensor frame S
//   /status        foxglove.Log             STATUS_* (process_status_t): health as the level,
//                                           counters and detail in the message
// Frames: rig A "O" (root), "O'", "L"; rig B "world" (root), "body", "L"; rig C "O_r" (root),
// "S". Timestamps are the messages' own utime; log_time_ns is the caller's (log or receive
// time). Messages that do not decode are skipped and counted (rejected()).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rigs/rig_file.hpp"

namespace sweepmap::viz {

struct FoxgloveSchema {
  std::string name;      // "foxglove.PointCloud"
  std::string encoding;  // "jsonschema"
  std::string data;      // the JSON schema's text
};

struct FoxgloveMessage {
  std::string topic;
  std::string schema_name;
  std::string json;  // message encoding "json"
  int64_t log_time_ns = 0;
};

// Every schema a FoxgloveConverter emits, in a fixed order.
const std::vector<FoxgloveSchema>& foxgloveSchemas();
// The schema named `name`, or nullptr.
const FoxgloveSchema* foxgloveSchema(const std::string& name);

// Each derived topic and its schema name, for advertising before any message exists.
const std::vector<std::pair<std::string, std::string>>& foxgloveTopics();

class FoxgloveConverter {
 public:
  // The rig's frames and mapper resolution come from `rig` (rigs/rig_file.hpp).
  explicit FoxgloveConverter(const Rig& rig);
  ~FoxgloveConverter();
  FoxgloveConverter(const FoxgloveConverter&) = delete;
  FoxgloveConverter& operator=(const FoxgloveConverter&) = delete;

  // The Foxglove messages one LCM message on `channel` gives (none for a channel without a
  // Foxglove view, or bytes that do not decode).
  std::vector<FoxgloveMessage> convert(const std::string& channel, const void* data,
                                       std::size_t size, int64_t log_time_ns);
  // The final map (if it changed since it was last emitted): call at the end of a log.
  std::vector<FoxgloveMessage> finish(int64_t log_time_ns);

  // Messages of a known channel that did not decode, by channel.
  const std::map<std::string, int64_t>& rejected() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace sweepmap::viz
