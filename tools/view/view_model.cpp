#include "tools/view/view_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/message_codec.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/profile_t.hpp"

namespace sweepmap {
namespace {

constexpr int kKeyBits = 21;
constexpr int64_t kKeyOffset = int64_t{1} << (kKeyBits - 1);
constexpr uint64_t kKeyMask = (uint64_t{1} << kKeyBits) - 1;

template <class T>
void putLe(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));  // the hosts we build for are little-endian
  out.append(b, sizeof(T));
}

std::string binaryHeader(BinaryFrame type, uint32_t n) {
  std::string h;
  putLe<uint8_t>(h, static_cast<uint8_t>(type));
  h.append(3, '\0');
  putLe<uint32_t>(h, n);
  return h;
}

ViewFrame control(const nlohmann::json& j, ViewFrame::Effect effect = ViewFrame::kNone,
                  int64_t sweep = -1) {
  ViewFrame f;
  f.kind = ViewFrame::kControl;
  f.data = std::make_shared<const std::string>(j.dump());
  f.effect = effect;
  f.sweep = sweep;
  return f;
}

ViewFrame latest(const std::string& key, std::shared_ptr<const std::string> data, bool binary) {
  ViewFrame f;
  f.kind = ViewFrame::kLatest;
  f.key = key;
  f.binary = binary;
  f.data = std::move(data);
  return f;
}

ViewFrame bulk(std::string data, bool binary) {
  ViewFrame f;
  f.kind = ViewFrame::kBulk;
  f.binary = binary;
  f.data = std::make_shared<const std::string>(std::move(data));
  return f;
}

ViewFrame voxelBulk(std::string data, bool binary) {
  ViewFrame f = bulk(std::move(data), binary);
  f.effect = ViewFrame::kVoxels;
  return f;
}

// Packs a voxel's integer coordinates (a map_update_t index, or a point's floor(p / res));
// false when outside +-2^20 voxels.
template <typename T>
bool packIndex(const T& v, uint64_t* key) {
  uint64_t k = 0;
  for (int a = 0; a < 3; ++a) {
    if (!(v[a] >= -kKeyOffset && v[a] < kKeyOffset)) return false;  // also NaN
    k |= (static_cast<uint64_t>(static_cast<int64_t>(v[a]) + kKeyOffset) & kKeyMask)
         << (a * kKeyBits);
  }
  *key = k;
  return true;
}

// The key of the voxel a point falls in; false when it is not finite or outside +-2^20 voxels.
bool voxelKey(const float* p, double res, uint64_t* key) {
  const double v[3] = {std::floor(p[0] / res), std::floor(p[1] / res), std::floor(p[2] / res)};
  return packIndex(v, key);
}

std::string voxelFrame(const std::vector<uint64_t>& keys, double res, uint32_t flags = 0) {
  std::string out = binaryHeader(BinaryFrame::kVoxels, static_cast<uint32_t>(keys.size()));
  putLe<float>(out, static_cast<float>(res));
  putLe<uint32_t>(out, flags);
  for (uint64_t k : keys) {
    for (int a = 0; a < 3; ++a) {
      putLe<int32_t>(out, static_cast<int32_t>(
                              static_cast<int64_t>((k >> (a * kKeyBits)) & kKeyMask) - kKeyOffset));
    }
  }
  return out;
}

// Every 2^thinning-th point of `xyz` (the first one kept).
// Every 2^thinning-th of the n items of `width` floats each (xyz: 3, intensity: 1).
std::vector<float> decimate(const float* values, size_t n, int thinning, size_t width = 3) {
  const size_t stride = size_t{1} << thinning;
  std::vector<float> out;
  out.reserve((n + stride - 1) / stride * width);
  for (size_t i = 0; i < n; i += stride) {
    out.insert(out.end(), values + width * i, values + width * i + width);
  }
  return out;
}

}  // namespace

ViewModel::ViewModel(const ViewModelOptions& options, Sink sink)
    : options_(options), sink_(std::move(sink)), board_(options.board) {}

void ViewModel::add(const Message& msg, int64_t now_utime) {
  ++counters_.messages;
  now_utime_ = now_utime;
  board_.add(msg, now_utime);
  if (msg.channel == channels::kSweepCloud) {
    addCloud(msg);
  } else if (msg.channel == channels::kMapUpdate) {
    addMapUpdate(msg);
  } else if (msg.channel == channels::kOdometryPose) {
    addPose(msg);
  } else if (msg.channel == channels::kLidarScan) {
    addScan(msg);
  } else if (msg.channel == channels::kProfile) {
    addProfile(msg);
  }
}

void ViewModel::reset() {
  sweeps_.clear();
  cloud_to_view_.clear();
  points_on_screen_ = 0;
  voxels_.clear();
  voxels_from_mapper_ = false;
  mapper_res_ = 0.0;
  last_update_seq_ = 0;
  full_seq_ = 0;
  full_keys_.clear();
  counters_.mapper_occupied_voxels = -1;
  path_.clear();
  last_pose_.clear();
  last_scan_utime_ = 0;
  last_scan_.reset();
  board_ = StatusBoard(options_.board);
  sink_(control({{"type", "reset"}}, ViewFrame::kReset));
}

ViewModel::ViewSweep& ViewModel::sweepFor(int64_t utime, int64_t cloud_sweep, int chunk_count,
                                          const std::string& frame) {
  const auto key = std::make_pair(utime, cloud_sweep);
  if (auto it = cloud_to_view_.find(key); it != cloud_to_view_.end()) {
    if (auto s = sweeps_.find(it->second); s != sweeps_.end()) return s->second;
  }
  // One-chunk clouds (rig B: a scan; rig C: a profile) join the newest view sweep while it
  // is small and, outside the world frame, of the same turntable sweep.
  if (chunk_count == 1 && !sweeps_.empty()) {
    ViewSweep& last = sweeps_.rbegin()->second;
    if (last.grouped && last.points < kGroupPoints &&
        (frame == "world" || last.cloud_sweep == cloud_sweep)) {
      cloud_to_view_[key] = last.id;
      return last;
    }
  }
  if (cloud_to_view_.size() > 100'000) cloud_to_view_.clear();  // bounded; old keys are done
  ViewSweep& s = sweeps_[next_sweep_id_];
  s.id = next_sweep_id_++;
  s.utime = utime;
  s.cloud_sweep = cloud_sweep;
  s.grouped = chunk_count == 1;
  cloud_to_view_[key] = s.id;
  return s;
}

void ViewModel::addCloud(const Message& msg) {
  cloud_chunk_t c;
  if (!decodeMessage(msg.data.data(), msg.data.size(), &c) || c.npoints < 0 ||
      c.xyz_m.size() != static_cast<size_t>(c.npoints)) {
    ++counters_.malformed;
    return;
  }
  ++counters_.chunks;
  counters_.points_received += c.npoints;
  ViewSweep& s = sweepFor(c.utime, c.sweep_id, c.chunk_count, c.frame);
  for (int a = 0; a < 3; ++a) s.origin[a] = static_cast<float>(c.sensor_origin_m[a]);
  std::vector<float> xyz;
  xyz.reserve(c.xyz_m.size() * 3);
  for (const auto& p : c.xyz_m) xyz.insert(xyz.end(), p.begin(), p.end());
  Chunk chunk;
  chunk.received_utime = now_utime_;
  chunk.xyz = s.thinning == 0 ? std::move(xyz) : decimate(xyz.data(), xyz.size() / 3, s.thinning);
  if (c.intensities.size() == c.xyz_m.size() && c.nintensities > 0) {
    chunk.intensity = decimate(c.intensities.data(), c.intensities.size(), s.thinning, 1);
  }
  if (!voxels_from_mapper_) addVoxels(chunk.xyz);
  const size_t n = chunk.xyz.size() / 3;
  s.points += n;
  points_on_screen_ += n;
  s.chunks.push_back(std::move(chunk));
  sink_(cloudFrame(s, s.chunks.back()));
  keepBudget();
}

ViewFrame ViewModel::cloudFrame(const ViewSweep& s, const Chunk& c) const {
  const uint32_t n = static_cast<uint32_t>(c.xyz.size() / 3);
  std::string out = binaryHeader(BinaryFrame::kCloud, n);
  putLe<int64_t>(out, s.id);
  putLe<int64_t>(out, s.utime);
  putLe<int64_t>(out, c.received_utime);
  for (float o : s.origin) putLe<float>(out, o);
  const bool with_intensity = !c.intensity.empty();
  putLe<uint32_t>(out, with_intensity ? kCloudHasIntensity : 0u);
  out.append(reinterpret_cast<const char*>(c.xyz.data()), c.xyz.size() * sizeof(float));
  out.append(reinterpret_cast<const char*>(c.intensity.data()), c.intensity.size() * sizeof(float));
  ViewFrame f = bulk(std::move(out), true);
  f.sweep = s.id;
  f.points = n;
  f.effect = ViewFrame::kAddPoints;
  return f;
}

void ViewModel::thin(ViewSweep& s) {
  size_t kept = 0;
  for (Chunk& c : s.chunks) {
    c.xyz = decimate(c.xyz.data(), c.xyz.size() / 3, 1);
    if (!c.intensity.empty()) c.intensity = decimate(c.intensity.data(), c.intensity.size(), 1, 1);
    kept += c.xyz.size() / 3;
  }
  points_on_screen_ -= s.points - kept;
  s.points = kept;
  ++s.thinning;
  ++counters_.thinned;
  sink_(control({{"type", "thin"}, {"sweep", s.id}}, ViewFrame::kThin, s.id));
}

// Oldest first: the oldest view sweep still above 1/2^kMaxThinning is thinned; when all are
// there, the oldest is removed. The newest sweep is thinned last of all.
void ViewModel::keepBudget() {
  while (points_on_screen_ > options_.point_budget && !sweeps_.empty()) {
    ViewSweep* victim = nullptr;
    for (auto& [id, s] : sweeps_) {
      if (s.thinning < kMaxThinning && s.points > 0) {
        victim = &s;
        break;
      }
    }
    if (victim) {
      thin(*victim);
      continue;
    }
    auto oldest = sweeps_.begin();
    points_on_screen_ -= oldest->second.points;
    ++counters_.removed_sweeps;
    sink_(
        control({{"type", "remove"}, {"sweep", oldest->first}}, ViewFrame::kRemove, oldest->first));
    sweeps_.erase(oldest);
  }
}

void ViewModel::addVoxels(const std::vector<float>& xyz) {
  std::vector<uint64_t> fresh;
  for (size_t i = 0; i + 2 < xyz.size(); i += 3) {
    uint64_t key;
    if (!voxelKey(&xyz[i], options_.voxel_m, &key)) continue;
    auto it = voxels_.find(key);
    if (it != voxels_.end()) {
      ++it->second;
    } else if (voxels_.size() >= options_.max_voxels) {
      ++counters_.voxels_refused;
    } else {
      voxels_.emplace(key, 1);
      fresh.push_back(key);
    }
  }
  if (!fresh.empty()) sink_(voxelBulk(voxelFrame(fresh, options_.voxel_m), true));
}

double ViewModel::voxelRes() const { return voxels_from_mapper_ ? mapper_res_ : options_.voxel_m; }

// One MAP_UPDATE chunk: its voxels added to and removed from the set, and the same to the
// pages (a "voxels" control frame first, which empties the pages' voxels). A full update's
// chunks list every occupied voxel: once all of them came, the voxels they did not list go.
void ViewModel::addMapUpdate(const Message& msg) {
  map_update_t u;
  if (!decodeMessage(msg.data.data(), msg.data.size(), &u) || !validateMapUpdate(u).empty()) {
    ++counters_.malformed;
    ++counters_.map_updates_invalid;
    return;
  }
  ++counters_.map_updates;
  // The first update, or a mapper that started again (seq back, or another resolution): the
  // set starts empty, and the pages' too.
  if (!voxels_from_mapper_ || u.resolution_m != mapper_res_ || u.seq < last_update_seq_) {
    voxels_.clear();
    voxels_from_mapper_ = true;
    mapper_res_ = u.resolution_m;
    last_update_seq_ = 0;
    sink_(control({{"type", "voxels"}, {"source", "mapper"}, {"voxel_m", mapper_res_}}));
  }
  if (last_update_seq_ != 0 && u.seq > last_update_seq_ + 1) {
    counters_.map_update_gaps += u.seq - last_update_seq_ - 1;
  }
  last_update_seq_ = std::max(last_update_seq_, u.seq);
  counters_.mapper_occupied_voxels = u.occupied_voxels;
  if (u.full && u.chunk_index == 0) {
    full_seq_ = u.seq;
    full_chunks_ = 0;
    full_keys_.clear();
  }
  const bool in_full = u.full && u.seq == full_seq_;
  full_chunks_ += in_full ? 1 : 0;
  std::vector<uint64_t> added, removed;
  for (const auto& v : u.occupied) {
    uint64_t key;
    if (!packIndex(v, &key)) continue;
    if (in_full) full_keys_.insert(key);
    if (voxels_.count(key)) continue;
    if (voxels_.size() >= options_.max_voxels) {
      ++counters_.voxels_refused;
      continue;
    }
    voxels_.emplace(key, 1);
    added.push_back(key);
  }
  for (const auto& v : u.freed) {
    uint64_t key;
    if (packIndex(v, &key) && voxels_.erase(key)) removed.push_back(key);
  }
  if (u.full && u.chunk_index == u.chunk_count - 1) removed = endFullUpdate(u.seq, u.chunk_count);
  if (!added.empty()) sink_(voxelBulk(voxelFrame(added, mapper_res_), true));
  if (!removed.empty()) sink_(voxelBulk(voxelFrame(removed, mapper_res_, kVoxelsRemoved), true));
}

// The last chunk of a full update: with every chunk received, the voxels it did not list are
// no longer occupied (returned, sorted); with one missing, nothing is removed and a gap counted.
std::vector<uint64_t> ViewModel::endFullUpdate(int64_t seq, int chunk_count) {
  std::vector<uint64_t> gone;
  if (full_seq_ != seq || full_chunks_ != chunk_count) {
    ++counters_.map_update_gaps;
  } else {
    for (const auto& [key, hits] : voxels_) {
      if (!full_keys_.count(key)) gone.push_back(key);
    }
    std::sort(gone.begin(), gone.end());
    for (const uint64_t key : gone) voxels_.erase(key);
  }
  full_seq_ = 0;
  full_keys_.clear();
  return gone;
}

void ViewModel::addPose(const Message& msg) {
  pose2d_t p;
  if (!decodeMessage(msg.data.data(), msg.data.size(), &p) || !std::isfinite(p.x_m) ||
      !std::isfinite(p.y_m) || !std::isfinite(p.theta_rad)) {
    ++counters_.malformed;
    return;
  }
  nlohmann::json j = {{"type", "pose"}, {"utime", p.utime},     {"x", p.x_m},
                      {"y", p.y_m},     {"theta", p.theta_rad}, {"trusted", p.trusted}};
  last_pose_ = j.dump();
  sink_(latest("pose", std::make_shared<const std::string>(last_pose_), false));
  const size_t n = path_.size();
  if (n >= 2 && std::hypot(p.x_m - path_[n - 2], p.y_m - path_[n - 1]) < options_.path_step_m) {
    return;
  }
  if (n / 2 >= options_.max_path_points) path_.erase(path_.begin(), path_.begin() + n / 2);
  path_.push_back(static_cast<float>(p.x_m));
  path_.push_back(static_cast<float>(p.y_m));
  sink_(bulk(nlohmann::json({{"type", "path"}, {"xy", {p.x_m, p.y_m}}}).dump(), false));
}

void ViewModel::addScan(const Message& msg) {
  lidar_scan_t s;
  if (!decodeMessage(msg.data.data(), msg.data.size(), &s)) {
    ++counters_.malformed;
    return;
  }
  if (last_scan_utime_ != 0 && s.utime - last_scan_utime_ < options_.scan_period_s * 1e6 &&
      s.utime >= last_scan_utime_) {
    return;
  }
  std::vector<float> yz;
  yz.reserve(s.ranges_m.size() * 2);
  for (size_t i = 0; i < s.ranges_m.size(); ++i) {
    const float r = s.ranges_m[i];
    if (!(r > 0.0f) || !std::isfinite(r)) continue;
    const float a = s.nangles == s.nranges ? s.angles_rad[i]
                                           : s.angle_min_rad + s.angle_increment_rad * float(i);
    yz.push_back(r * std::sin(a));  // p_L = r [0, sin a, cos a] (Yuan 2021 Eq. 4)
    yz.push_back(r * std::cos(a));
  }
  emitScan(s.utime, yz);
}

void ViewModel::addProfile(const Message& msg) {
  profile_t p;
  if (!decodeMessage(msg.data.data(), msg.data.size(), &p)) {
    ++counters_.malformed;
    return;
  }
  if (last_scan_utime_ != 0 && p.utime - last_scan_utime_ < options_.scan_period_s * 1e6 &&
      p.utime >= last_scan_utime_) {
    return;
  }
  std::vector<float> yz;
  for (size_t i = 0; i < p.y_mm.size() && i < p.z_mm.size(); ++i) {
    yz.push_back(p.y_mm[i] * 1e-3f);
    yz.push_back(p.z_mm[i] * 1e-3f);
  }
  emitScan(p.utime, yz);
}

void ViewModel::emitScan(int64_t utime, const std::vector<float>& yz) {
  last_scan_utime_ = utime;
  std::string out = binaryHeader(BinaryFrame::kScan, static_cast<uint32_t>(yz.size() / 2));
  putLe<int64_t>(out, utime);
  out.append(reinterpret_cast<const char*>(yz.data()), yz.size() * sizeof(float));
  last_scan_ = std::make_shared<const std::string>(std::move(out));
  sink_(latest("scan", last_scan_, true));
}

std::vector<ViewFrame> ViewModel::voxelSnapshot() const {
  std::vector<ViewFrame> out;
  out.push_back(control({{"type", "voxels"},
                         {"source", voxels_from_mapper_ ? "mapper" : "points"},
                         {"voxel_m", voxelRes()}}));
  std::vector<uint64_t> keys;
  keys.reserve(voxels_.size());
  for (const auto& [key, hits] : voxels_) keys.push_back(key);
  std::sort(keys.begin(), keys.end());  // the hash map's order must not reach the pages
  for (size_t i = 0; i < keys.size(); i += 65536) {
    const std::vector<uint64_t> part(
        keys.begin() + static_cast<std::ptrdiff_t>(i),
        keys.begin() + static_cast<std::ptrdiff_t>(std::min(keys.size(), i + 65536)));
    out.push_back(voxelBulk(voxelFrame(part, voxelRes()), true));
  }
  return out;
}

std::vector<ViewFrame> ViewModel::snapshot() const {
  std::vector<ViewFrame> out;
  for (const auto& [id, s] : sweeps_) {
    for (const Chunk& c : s.chunks) out.push_back(cloudFrame(s, c));
  }
  for (ViewFrame& f : voxelSnapshot()) out.push_back(std::move(f));
  if (!path_.empty()) {
    nlohmann::json xy = nlohmann::json::array();
    for (float v : path_) xy.push_back(v);
    out.push_back(bulk(nlohmann::json({{"type", "path"}, {"xy", xy}}).dump(), false));
  }
  if (!last_pose_.empty()) {
    out.push_back(latest("pose", std::make_shared<const std::string>(last_pose_), false));
  }
  if (last_scan_) out.push_back(latest("scan", last_scan_, true));
  return out;
}

}  // namespace sweepmap
