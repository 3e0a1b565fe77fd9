#include "processes/mapper_node.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "mapping/occupancy_map.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "sweepmap/map_save_t.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "sweepmap/sweep_status_t.hpp"

namespace sweepmap {

MapperNode::MapperNode(const MapperConfig& config, std::string save_path, int save_every)
    : Node("mapper"),
      config_(config),
      save_path_(std::move(save_path)),
      save_every_(save_every),
      map_(std::make_unique<OccupancyMap>(config)) {}

MapperNode::~MapperNode() = default;

std::vector<std::string> MapperNode::subscriptions() const {
  return {channels::kSweepCloud, channels::kSweepStatus, channels::kMapSave};
}

void MapperNode::handle(const Message& msg, Outbox& out) {
  if (msg.channel == channels::kSweepCloud) {
    cloud_chunk_t c;
    if (!decodeMessage(msg, &c)) {
      reportError("invalid", "malformed cloud_chunk_t");
      return;
    }
    const std::string why = validateChunk(c);
    if (!why.empty()) {
      reportError("invalid", "chunk of sweep " + std::to_string(c.sweep_id) + " dropped: " + why);
      return;
    }
    const SweepKey key{c.utime, c.sweep_id};
    if (inserted_.count(key)) {
      reportError("dropped", "late chunk of already inserted sweep " + std::to_string(c.sweep_id));
      return;
    }
    // A newer sweep begins: older pending sweeps will not complete any more.
    while (!pending_.empty() && pending_.begin()->first < key) {
      insert(msg.utime, pending_.begin()->first, out);
    }
    PendingSweep& p = pending_[key];
    p.chunk_count = c.chunk_count;
    p.origin = Eigen::Vector3d(c.sensor_origin_m[0], c.sensor_origin_m[1], c.sensor_origin_m[2])
                   .cast<float>();
    std::vector<float>& xyz = p.chunks[c.chunk_index];
    xyz.clear();
    xyz.reserve(c.xyz_m.size() * 3);
    for (const auto& q : c.xyz_m) xyz.insert(xyz.end(), q.begin(), q.end());
    last_sweep_utime_ = c.utime;
    count("chunks");
  } else if (msg.channel == channels::kSweepStatus) {
    sweep_status_t s;
    if (!decodeMessage(msg, &s)) {
      reportError("invalid", "malformed sweep_status_t");
      return;
    }
    const SweepKey key{s.utime, s.sweep_id};
    if (pending_.count(key)) insert(msg.utime, key, out);
  } else if (msg.channel == channels::kMapSave) {
    map_save_t r;
    if (!decodeMessage(msg, &r)) {
      reportError("invalid", "malformed map_save_t");
      return;
    }
    if (save_path_.empty()) {
      reportError("errors", "MAP_SAVE: this mapper has no --save path");
      return;
    }
    // Only a file name is taken from the request: the map stays in save_path's directory.
    const std::filesystem::path name = std::filesystem::path(r.path).filename();
    if (!r.path.empty() && (name.empty() || name == "." || name == "..")) {
      reportError("invalid", "MAP_SAVE: bad file name '" + r.path + "'");
      return;
    }
    flushBatch(msg.utime, out);  // a save holds every sweep received so far
    save(r.path.empty() ? save_path_
                        : (std::filesystem::path(save_path_).parent_path() / name).string());
  }
}

void MapperNode::insert(int64_t now_utime, SweepKey key, Outbox& out) {
  const int64_t sweep_id = key.second;
  auto it = pending_.find(key);
  if (it == pending_.end()) return;
  std::vector<Eigen::Vector3f> points;
  for (const auto& [index, xyz] : it->second.chunks) {
    for (size_t i = 0; i + 2 < xyz.size(); i += 3)
      points.emplace_back(xyz[i], xyz[i + 1], xyz[i + 2]);
  }
  if (static_cast<int>(it->second.chunks.size()) != it->second.chunk_count) {
    ++incomplete_;
    reportError("incomplete_sweeps", "sweep " + std::to_string(sweep_id) + " inserted with " +
                                         std::to_string(it->second.chunks.size()) + " of " +
                                         std::to_string(it->second.chunk_count) + " chunks");
  }
  const Eigen::Vector3f it_origin = it->second.origin;
  pending_.erase(it);
  inserted_.insert(key);
  while (inserted_.size() > 1000) inserted_.erase(inserted_.begin());
  if (config_.batch_s > 0.0) {
    const int64_t batch_us = std::max<int64_t>(1, std::llround(config_.batch_s * 1e6));
    // Floor division: windows [k * batch_us, (k + 1) * batch_us) also for negative times.
    const int64_t window = key.first / batch_us - (key.first % batch_us < 0 ? 1 : 0);
    if (!batch_.empty() && window != batch_window_) flushBatch(now_utime, out);
    batch_window_ = window;
    batch_.push_back(SensorCloud{std::move(points), it_origin});
    batch_sweep_ids_.push_back(sweep_id);
    return;
  }
  try {
    map_->insertCloud(points, it_origin);
  } catch (const std::exception& e) {
    reportError("invalid", "sweep " + std::to_string(sweep_id) + " not inserted: " + e.what());
    return;
  }
  ++sweeps_inserted_;
  count("sweeps");
  publishStats(now_utime, out);
  autosave();
}

void MapperNode::flushBatch(int64_t now_utime, Outbox& out) {
  if (batch_.empty()) return;
  std::vector<size_t> rejected;
  map_->insertClouds(batch_, &rejected);
  for (const size_t i : rejected) {
    reportError("invalid", "sweep " + std::to_string(batch_sweep_ids_[i]) +
                               " not inserted: non-finite sensor origin or outside the map");
  }
  const int64_t inserted = static_cast<int64_t>(batch_.size() - rejected.size());
  batch_.clear();
  batch_sweep_ids_.clear();
  if (inserted == 0) return;
  sweeps_inserted_ += inserted;
  count("sweeps", inserted);
  publishStats(now_utime, out);
  autosave();
}

void MapperNode::autosave() {
  if (save_every_ <= 0 || save_path_.empty() || ++updates_since_save_ < save_every_) return;
  updates_since_save_ = 0;
  save(save_path_);
}

void MapperNode::publishStats(int64_t now_utime, Outbox& out) {
  const MapStats st = map_->stats();
  map_stats_t m;
  m.utime = last_sweep_utime_;
  m.sweeps_inserted = sweeps_inserted_;
  m.points_inserted = st.points_inserted;
  m.resolution_m = st.resolution_m;
  m.occupied_voxels = st.occupied_voxels;
  m.free_voxels = st.free_voxels;
  m.memory_bytes = st.memory_bytes;
  m.incomplete_sweeps = incomplete_;
  out.publish(channels::kMapStats, now_utime, m);
}

void MapperNode::save(const std::string& path) {
  try {
    map_->saveBinaryAtomic(path);
    count("saves");
  } catch (const std::exception& e) {
    reportError("save_errors", e.what());
  }
}

void MapperNode::finish(int64_t now_utime, Outbox& out) {
  while (!pending_.empty()) insert(now_utime, pending_.begin()->first, out);
  flushBatch(now_utime, out);
  if (!save_path_.empty()) save(save_path_);
}

}  // namespace sweepmap
