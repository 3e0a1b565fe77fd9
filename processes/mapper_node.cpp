#include "processes/mapper_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>

#include "mapping/occupancy_map.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "sweepmap/map_save_t.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "sweepmap/map_update_t.hpp"
#include "sweepmap/sweep_status_t.hpp"

namespace sweepmap {

MapperNode::MapperNode(const MapperConfig& config, std::string save_path, int save_every)
    : Node("mapper"),
      config_(config),
      save_path_(std::move(save_path)),
      save_every_(save_every),
      map_(std::make_unique<OccupancyMap>(config)) {
  map_->trackChanges();
}

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
    pending_points_ -= xyz.size() / 3;  // a repeated chunk replaces its first copy
    xyz.clear();
    xyz.reserve(c.xyz_m.size() * 3);
    for (const auto& q : c.xyz_m) xyz.insert(xyz.end(), q.begin(), q.end());
    pending_points_ += c.xyz_m.size();
    last_sweep_utime_ = c.utime;
    boundPending(msg.utime, out);
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
    handleMapSave(msg, out);
  }
}

void MapperNode::handleMapSave(const Message& msg, Outbox& out) {
  map_save_t r;
  if (!decodeMessage(msg, &r)) {
    reportError("invalid", "malformed map_save_t");
    return;
  }
  if (save_path_.empty()) {
    reportError("refused_saves", "MAP_SAVE: this mapper has no --save path");
    return;
  }
  // Only a file name is taken from the request: the map stays in save_path's folder.
  const std::string name =
      std::filesystem::path(r.path.empty() ? save_path_ : r.path).filename().string();
  if (const std::string why = refuseMapSave(name, msg.utime); !why.empty()) {
    reportError("refused_saves", "MAP_SAVE refused: " + why);
    return;
  }
  last_requested_save_utime_ = msg.utime;
  requested_save_done_ = true;
  flushBatch(msg.utime, out);  // a save holds every sweep received so far
  save((std::filesystem::path(save_path_).parent_path() / name).string());
}

std::string MapperNode::refuseMapSave(const std::string& name, int64_t utime) const {
  static const std::regex kSafeName("[A-Za-z0-9][A-Za-z0-9_.-]{0,63}\\.bt");
  std::string shown = name.substr(0, 80);
  for (char& c : shown) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) c = '?';
  }
  if (!std::regex_match(name, kSafeName)) {
    return "'" + shown + "' is not a file name of the pattern [A-Za-z0-9][A-Za-z0-9_.-]{0,63}.bt";
  }
  if (requested_save_done_ &&
      utime - last_requested_save_utime_ < static_cast<int64_t>(config_.save_interval_s * 1e6)) {
    char text[64];
    std::snprintf(text, sizeof text, "one request per %g s (mapper.save_interval_s)",
                  config_.save_interval_s);
    return text;
  }
  const bool own = name == std::filesystem::path(save_path_).filename().string();
  const size_t max_files = static_cast<size_t>(config_.max_requested_files);
  if (!own && !written_.count(name) && written_.size() >= max_files + 1) {
    return "this mapper has written " + std::to_string(max_files) +
           " requested files already (mapper.max_requested_files)";
  }
  const std::filesystem::path target = std::filesystem::path(save_path_).parent_path() / name;
  std::error_code ec;
  if (!own && !written_.count(name) && std::filesystem::exists(target, ec)) {
    return "'" + shown + "' exists and was not written by this mapper";
  }
  return {};
}

// Sweeps that never complete (a lost status, a forged chunk) must not pile up: over the bounds,
// the oldest pending sweep goes into the map as it is.
void MapperNode::boundPending(int64_t now_utime, Outbox& out) {
  while (
      pending_.size() > static_cast<size_t>(config_.max_pending_sweeps) ||
      (pending_points_ > static_cast<size_t>(config_.max_pending_points) && pending_.size() > 1)) {
    count("pending_evicted");
    insert(now_utime, pending_.begin()->first, out);
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
  pending_points_ -= points.size();
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
  publishUpdate(now_utime, sweep_id, out);
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
  const int64_t last_sweep_id = batch_sweep_ids_.back();
  batch_.clear();
  batch_sweep_ids_.clear();
  if (inserted == 0) return;
  sweeps_inserted_ += inserted;
  count("sweeps", inserted);
  publishUpdate(now_utime, last_sweep_id, out);
  publishStats(now_utime, out);
  autosave();
}

void MapperNode::autosave() {
  if (save_every_ <= 0 || save_path_.empty() || ++updates_since_save_ < save_every_) return;
  updates_since_save_ = 0;
  save(save_path_);
}

void MapperNode::publishUpdate(int64_t now_utime, int64_t sweep_id, Outbox& out) {
  VoxelChanges changes = map_->takeChanges();
  map_update_t header{};
  header.utime = last_sweep_utime_;
  header.seq = ++update_seq_;
  header.full = (header.seq - 1) % kFullUpdateEvery == 0;  // a late viewer catches up
  if (header.full) changes = VoxelChanges{map_->trackedVoxels(), {}};
  header.sweep_id = sweep_id;
  header.resolution_m = map_->config().resolution_m;
  header.occupied_voxels = map_->stats().occupied_voxels;
  for (const map_update_t& m : toMapUpdates(changes.occupied, changes.freed, header)) {
    out.publish(channels::kMapUpdate, now_utime, m);
  }
  count("map_update_voxels", static_cast<int64_t>(changes.occupied.size() + changes.freed.size()));
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
    written_.insert(std::filesystem::path(path).filename().string());
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
