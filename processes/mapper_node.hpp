// sweepmap-mapper: gathers the chunks of each sweep from SWEEP_CLOUD and inserts the
// sweep into an OctoMap OcTree (sensor at the origin of the sweep's frame). After each map
// update (a sweep, or a batch) it publishes MAP_UPDATE, the voxels that update made occupied
// or freed (OccupancyMap::takeChanges(); lcmtypes/map_update_t.lcm), then MAP_STATS. It saves
// the map (.bt, written atomically) on MAP_SAVE and at finish(). A sweep is inserted when its
// SWEEP_STATUS arrives or a later sweep starts; missing chunks cost only their points and are
// counted.
//
// Batches (config.batch_s > 0, rig B: one small sweep per lidar scan): sweeps whose time
// (the SWEEP_CLOUD utime) falls in the same batch_s window, counted from utime 0, are
// inserted together once a sweep of a later window is ready, before a save and at
// finish() (OccupancyMap::insertClouds: the map is exactly the one that sweep-by-sweep
// insertion builds, only the whole-tree updates are shared), and MAP_STATS goes out once
// per batch. Batches depend on message content only, so live and offline runs agree.
#pragma once

#include <Eigen/Core>
#include <map>
#include <memory>
#include <set>

#include "core/rig_components.hpp"
#include "mapping/occupancy_map.hpp"
#include "processes/node.hpp"

namespace sweepmap {

class MapperNode : public Node {
 public:
  // MAP_UPDATE number 1, 1 + kFullUpdateEvery, ... lists the whole occupied set (`full`).
  static constexpr int64_t kFullUpdateEvery = 20;
  // `save_path`: where the map goes at finish() and on a MAP_SAVE request ("" = none). A
  // request may name another file, but only inside save_path's directory. `save_every` > 0:
  // also after every that many map updates (a sweep, or a batch of a mobile rig), so that a
  // process killed (kill -9, power loss) leaves its last saved map behind.
  //
  // A MAP_SAVE request comes from the network: it is a request, not a command. It is honoured
  // only for a name of the pattern [A-Za-z0-9][A-Za-z0-9_.-]{0,63}.bt, never over a file this
  // mapper did not write, at most once every config.save_interval_s and for at most
  // config.max_requested_files names per run; everything refused is counted (`refused_saves`).
  // Sweeps being assembled are bounded too (config.max_pending_sweeps, max_pending_points): the
  // oldest goes into the map as it is (counted as `pending_evicted`) when a bound is reached.
  MapperNode(const MapperConfig& config, std::string save_path, int save_every = 0);
  ~MapperNode() override;
  std::vector<std::string> subscriptions() const override;
  void finish(int64_t now_utime, Outbox& out) override;
  const OccupancyMap& map() const { return *map_; }

 protected:
  void handle(const Message& msg, Outbox& out) override;

 private:
  // A sweep is identified by (window start, sweep id): ids start again at 0 when the motor
  // process restarts.
  using SweepKey = std::pair<int64_t, int64_t>;
  struct PendingSweep {
    int chunk_count = 0;
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();
    std::map<int, std::vector<float>> chunks;  // chunk index -> xyz triples
  };
  // Inserts the pending sweep `key` and erases it from pending_. The key is taken by value:
  // callers pass pending_.begin()->first, which the erase would free.
  void insert(int64_t now_utime, SweepKey key, Outbox& out);
  void flushBatch(int64_t now_utime, Outbox& out);
  // MAP_UPDATE: what the insertion just made changed in the map (OccupancyMap::takeChanges()).
  void publishUpdate(int64_t now_utime, int64_t sweep_id, Outbox& out);
  void publishStats(int64_t now_utime, Outbox& out);
  void autosave();
  void save(const std::string& path);
  void handleMapSave(const Message& msg, Outbox& out);
  // Why a MAP_SAVE to `name` is refused ("" when it is not).
  std::string refuseMapSave(const std::string& name, int64_t utime) const;
  void boundPending(int64_t now_utime, Outbox& out);

  MapperConfig config_;
  std::string save_path_;
  int save_every_ = 0;
  int updates_since_save_ = 0;
  std::unique_ptr<OccupancyMap> map_;
  std::map<SweepKey, PendingSweep> pending_;
  std::set<SweepKey> inserted_;  // the last 1000 keys (late chunks)
  size_t pending_points_ = 0;
  std::set<std::string> written_;  // file names this mapper wrote in save_path's folder
  int64_t last_requested_save_utime_ = 0;
  bool requested_save_done_ = false;
  int64_t sweeps_inserted_ = 0;
  int64_t incomplete_ = 0;
  int64_t last_sweep_utime_ = 0;
  int64_t update_seq_ = 0;  // MAP_UPDATE's seq of the last update
  // Sweeps waiting for the end of their batch window (batch_s > 0).
  std::vector<SensorCloud> batch_;
  std::vector<int64_t> batch_sweep_ids_;
  int64_t batch_window_ = 0;
};

}  // namespace sweepmap
