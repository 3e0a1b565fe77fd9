// What `sweepmap view` shows, kept apart from the transport: fed the LCM messages of a run (live
// or from a log), it keeps the state a page needs (the clouds on screen within a point budget,
// the occupied voxels, the rig's path, the latest scan, every process's health) and turns each
// change into frames for the pages (binary for clouds, voxels and scans; JSON for the rest).
// It reads no clock (times come with the calls) and does no I/O, so tests drive it directly.
//
// Clouds: SWEEP_CLOUD chunks, grouped into "view sweeps" (a rig-A sweep is one; rig B's and rig
// C's one-chunk clouds are gathered up to kGroupPoints). When the points on screen pass the
// budget, the oldest view sweep is thinned first (every second point of each of its chunks
// dropped, a "thin" frame telling the pages to do the same), down to 1/2^kMaxThinning of its
// points; then the oldest view sweep is removed ("remove"). A chunk of a sweep already thinned
// is sent thinned. Pages apply the same arithmetic, so they draw exactly the points sent.
//
// Voxels: the mapper's OctoMap, kept from MAP_UPDATE (lcmtypes/map_update_t.lcm: each map
// update's voxels that became occupied or were freed), bounded by max_voxels; each update goes
// to the pages as the voxels it adds and those it removes. Until a first MAP_UPDATE arrives (a
// log recorded before the mapper published it, or no mapper running), a fallback: the voxels
// the cloud points fall in at the mapper's resolution (a voxel shown occupied from its first
// point; rays clearing space are not modelled). The first MAP_UPDATE replaces those with the
// mapper's voxels (a "voxels" control frame tells the pages the source). A full update (the
// mapper's first, and every 20th) lists every occupied voxel: a view started late, or one that
// lost an update, has the mapper's set again after it.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "processes/node.hpp"
#include "tools/ops/status.hpp"

namespace sweepmap {

// One frame for the pages. kControl frames are never dropped (small: reset, thin, remove);
// kBulk frames (clouds, voxels, path) may be dropped by a client's bounded queue, oldest first,
// and are counted; kLatest frames replace a queued frame of the same key (newest wins: pose,
// scan, time).
struct ViewFrame {
  enum Kind { kControl, kBulk, kLatest };
  Kind kind = kControl;
  bool binary = false;
  std::shared_ptr<const std::string> data;
  std::string key;      // kLatest: what it replaces
  int64_t sweep = -1;   // a cloud chunk's view sweep (for the per-client point count)
  uint32_t points = 0;  // a cloud chunk's points
  // kVoxels: a voxel frame (added or removed); a page that misses one is resynchronised
  // (ClientQueue::takeVoxelsStale, ViewModel::voxelSnapshot).
  enum Effect { kNone, kAddPoints, kThin, kRemove, kReset, kVoxels } effect = kNone;
};

// Binary frame types (first byte; little-endian; header sizes are multiples of 4).
//  1 cloud chunk: u8 type, u8[3] 0, u32 n, i64 view sweep, i64 utime [us] (the sweep's),
//    i64 received [us] (when the view took the chunk: wall clock live, log time from a log),
//    f32 sensor origin[3] [m], u32 flags (48 bytes), then n * f32 xyz [m], then, when flags has
//    kCloudHasIntensity, n * f32 intensity (the lidar's device units; absent for a lidar
//    without intensity, such as rig B's X4 and rig C's profiler).
//  2 voxels: u8 type, u8[3] 0, u32 n, f32 resolution [m], u32 flags (16 bytes), then n * i32
//    key[3] (the voxel [key*res, (key+1)*res) on each axis): added to the page's voxels, or,
//    when flags has kVoxelsRemoved, removed from them.
//  3 scan: u8 type, u8[3] 0, u32 n, i64 utime [us] (16 bytes), then n * f32 (y, z) [m] in the
//    scan plane (lidar: frame L's Y-Z; profiler: the sensor's y-z).
enum class BinaryFrame : uint8_t { kCloud = 1, kVoxels = 2, kScan = 3 };
constexpr uint32_t kCloudHasIntensity = 1;  // a cloud frame's flags
constexpr uint32_t kVoxelsRemoved = 1;      // a voxel frame's flags

struct ViewModelOptions {
  size_t point_budget = 2'000'000;  // points on screen
  double voxel_m = 0.05;            // the mapper's resolution
  size_t max_voxels = 2'000'000;
  size_t max_path_points = 100'000;
  double path_step_m = 0.05;   // a new path point when the pose moved this far
  double scan_period_s = 0.1;  // at most one scan frame per this much message time
  StatusBoardOptions board;
};

struct ViewModelCounters {
  int64_t messages = 0;
  int64_t malformed = 0;  // undecodable messages on a viewed channel
  int64_t chunks = 0;     // SWEEP_CLOUD chunks taken
  int64_t points_received = 0;
  int64_t thinned = 0;              // thinning steps of a view sweep
  int64_t removed_sweeps = 0;       // view sweeps removed for the budget
  int64_t voxels_refused = 0;       // new voxels beyond max_voxels
  int64_t map_updates = 0;          // MAP_UPDATE chunks applied
  int64_t map_updates_invalid = 0;  // MAP_UPDATE chunks refused (validateMapUpdate), in malformed
  int64_t map_update_gaps = 0;      // updates (or a full update's chunks) missed: the voxels may
                                    // differ until the next full update
  int64_t mapper_occupied_voxels = -1;  // the mapper's count after the last update (-1: none)
};

class ViewModel {
 public:
  using Sink = std::function<void(const ViewFrame&)>;
  static constexpr int kMaxThinning = 6;  // down to 1/64 of a sweep before it is removed
  static constexpr size_t kGroupPoints = 50'000;

  ViewModel(const ViewModelOptions& options, Sink sink);
  // A message received (or played) at now_utime; frames go to the sink in order.
  void add(const Message& msg, int64_t now_utime);
  // Everything forgotten (a seek back in a log): a kReset frame first.
  void reset();
  // The frames that bring a new page to the current state, in order.
  std::vector<ViewFrame> snapshot() const;
  // The frames that replace a page's voxels with the current set: a "voxels" control frame
  // (the page empties its voxels) and the set, sorted. For a page that lost a voxel frame.
  std::vector<ViewFrame> voxelSnapshot() const;
  // The status board as JSON (tools/ops/status.hpp) at now_utime.
  std::string boardJson(int64_t now_utime) const { return board_.json(now_utime); }
  size_t pointsOnScreen() const { return points_on_screen_; }
  size_t voxels() const { return voxels_.size(); }
  // Whether the voxels are the mapper's (MAP_UPDATE), not the cloud-derived fallback.
  bool voxelsFromMapper() const { return voxels_from_mapper_; }
  const ViewModelCounters& counters() const { return counters_; }

 private:
  struct Chunk {
    std::vector<float> xyz;
    std::vector<float> intensity;  // empty, or one per point
    int64_t received_utime = 0;
  };
  struct ViewSweep {
    int64_t id = 0;
    int64_t utime = 0;
    int64_t cloud_sweep = 0;
    bool grouped = false;  // gathers one-chunk clouds
    int thinning = 0;      // every 2^thinning-th point kept
    float origin[3] = {0, 0, 0};
    std::vector<Chunk> chunks;
    size_t points = 0;
  };
  void addCloud(const Message& msg);
  ViewSweep& sweepFor(int64_t utime, int64_t cloud_sweep, int chunk_count,
                      const std::string& frame);
  void keepBudget();
  void thin(ViewSweep& s);
  void addVoxels(const std::vector<float>& xyz);
  void addMapUpdate(const Message& msg);
  std::vector<uint64_t> endFullUpdate(int64_t seq, int chunk_count);
  double voxelRes() const;
  void addPose(const Message& msg);
  void addScan(const Message& msg);
  void addProfile(const Message& msg);
  void emitScan(int64_t utime, const std::vector<float>& yz);
  ViewFrame cloudFrame(const ViewSweep& s, const Chunk& c) const;
  int64_t now_utime_ = 0;

  ViewModelOptions options_;
  Sink sink_;
  StatusBoard board_;
  std::map<int64_t, ViewSweep> sweeps_;  // by view sweep id (arrival order)
  std::map<std::pair<int64_t, int64_t>, int64_t> cloud_to_view_;  // (utime, sweep) -> view sweep
  int64_t next_sweep_id_ = 0;
  size_t points_on_screen_ = 0;
  std::unordered_map<uint64_t, uint32_t> voxels_;  // packed key -> points seen (1: the mapper's)
  bool voxels_from_mapper_ = false;
  double mapper_res_ = 0.0;  // MAP_UPDATE's resolution
  int64_t last_update_seq_ = 0;
  int64_t full_seq_ = 0;                    // the full update being received (0: none)
  int full_chunks_ = 0;                     // its chunks received
  std::unordered_set<uint64_t> full_keys_;  // the voxels its chunks listed
  std::vector<float> path_;                 // x, y pairs [m]
  std::string last_pose_;
  int64_t last_scan_utime_ = 0;
  std::shared_ptr<const std::string> last_scan_;
  ViewModelCounters counters_;
};

}  // namespace sweepmap
