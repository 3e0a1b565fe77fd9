#include "viz/foxglove_messages.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>
#include <variant>

#include "core/angles.hpp"
#include "core/profile_geometry.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/message_codec.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/map_update_t.hpp"
#include "sweepmap/motor_state_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "sweepmap/profile_t.hpp"

namespace sweepmap::viz {

const std::vector<std::pair<std::string, std::string>>& foxgloveSchemaSources();  // generated

namespace {

using nlohmann::json;

constexpr const char* kPointCloud = "foxglove.PointCloud";
constexpr const char* kPoseInFrame = "foxglove.PoseInFrame";
constexpr const char* kFrameTransform = "foxglove.FrameTransform";
constexpr const char* kLaserScan = "foxglove.LaserScan";
constexpr const char* kLog = "foxglove.Log";
constexpr int kFloat32 = 7;                   // foxglove.PackedElementField's type FLOAT32
constexpr int64_t kMapPeriodNs = 1000000000;  // /map at most once per second of log time

std::string base64(const std::vector<uint8_t>& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (bytes[i] << 16) | (bytes[i + 1] << 8) | bytes[i + 2];
    for (int k = 18; k >= 0; k -= 6) out += table[(v >> k) & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const uint32_t v = (bytes[i] << 16) | (two ? bytes[i + 1] << 8 : 0);
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += two ? table[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// JSON has no NaN: a non-finite number would not validate against the schemas.
double finite(double v) { return std::isfinite(v) ? v : 0.0; }

json timeJson(int64_t utime) {
  const int64_t us = std::max<int64_t>(utime, 0);
  return {{"sec", us / 1000000}, {"nsec", (us % 1000000) * 1000}};
}

json vec3Json(const Eigen::Vector3d& v) {
  return {{"x", finite(v.x())}, {"y", finite(v.y())}, {"z", finite(v.z())}};
}

json quatJson(const Eigen::Quaterniond& q) {
  return {{"x", finite(q.x())}, {"y", finite(q.y())}, {"z", finite(q.z())}, {"w", finite(q.w())}};
}

json poseJson(const Eigen::Isometry3d& T) {
  return {{"position", vec3Json(T.translation())},
          {"orientation", quatJson(Eigen::Quaterniond(T.linear()))}};
}

Eigen::Isometry3d rotationZ(double angle_rad, const Eigen::Vector3d& t = Eigen::Vector3d::Zero()) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = t;
  return T;
}

// The lidar frame L has its scan plane Y_L-Z_L with angles from Z_L toward Y_L (Yuan 2021
// Eq. 4); a foxglove.LaserScan measures angles in its x-y plane from x toward y. This pose
// (a rotation of -90 deg about y) puts the scan's x on Z_L and its y on Y_L.
Eigen::Isometry3d laserScanPoseInL() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T;
}

FoxgloveMessage message(const char* topic, const char* schema, const json& j, int64_t t_ns) {
  return {topic, schema, j.dump(), t_ns};
}

FoxgloveMessage frameTransform(const std::string& parent, const std::string& child,
                               const Eigen::Isometry3d& T, int64_t utime, int64_t t_ns) {
  json j = {{"timestamp", timeJson(utime)},
            {"parent_frame_id", parent},
            {"child_frame_id", child},
            {"translation", vec3Json(T.translation())},
            {"rotation", quatJson(Eigen::Quaterniond(T.linear()))}};
  return message("/tf", kFrameTransform, j, t_ns);
}

// A foxglove.PointCloud of float32 fields, packed point by point (`values` holds
// fields.size() floats per point).
json pointCloudJson(int64_t utime, const std::string& frame, const std::vector<std::string>& fields,
                    const std::vector<float>& values) {
  json field_list = json::array();
  for (size_t i = 0; i < fields.size(); ++i) {
    field_list.push_back({{"name", fields[i]}, {"offset", 4 * i}, {"type", kFloat32}});
  }
  std::vector<uint8_t> bytes(values.size() * 4);
  for (size_t i = 0; i < values.size(); ++i) {  // little-endian, as Foxglove reads
    uint32_t u;
    std::memcpy(&u, &values[i], 4);
    for (int b = 0; b < 4; ++b) bytes[4 * i + b] = static_cast<uint8_t>(u >> (8 * b));
  }
  return {{"timestamp", timeJson(utime)},
          {"frame_id", frame},
          {"pose", poseJson(Eigen::Isometry3d::Identity())},
          {"point_stride", 4 * fields.size()},
          {"fields", field_list},
          {"data", base64(bytes)}};
}

}  // namespace

const std::vector<FoxgloveSchema>& foxgloveSchemas() {
  static const std::vector<FoxgloveSchema> schemas = [] {
    std::vector<FoxgloveSchema> out;
    for (const auto& [name, text] : foxgloveSchemaSources()) {
      out.push_back({name, "jsonschema", text});
    }
    return out;
  }();
  return schemas;
}

const FoxgloveSchema* foxgloveSchema(const std::string& name) {
  for (const auto& s : foxgloveSchemas()) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

const std::vector<std::pair<std::string, std::string>>& foxgloveTopics() {
  static const std::vector<std::pair<std::string, std::string>> topics = {
      {"/sweep_cloud", kPointCloud}, {"/map", kPointCloud},
      {"/pose", kPoseInFrame},       {"/wheel_odometry", kPoseInFrame},
      {"/truth_pose", kPoseInFrame}, {"/tf", kFrameTransform},
      {"/lidar_scan", kLaserScan},   {"/lidar_points", kPointCloud},
      {"/profile", kPointCloud},     {"/status", kLog}};
  return topics;
}

struct FoxgloveConverter::State {
  RigKind kind = RigKind::kRotatingLidar;
  double resolution_m = 0.05;
  double lidar_offset_x_m = 0.0;                                   // rig A: t_L^O'
  Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();  // rig B
  int64_t lidar_time_offset_us = 0;  // rig B: scans go on the poses' clock (lidar.time_offset_s)
  ProfileGeometry profile_geometry;  // rig C
  bool static_sent = false;
  double last_phi_offset = NAN;
  std::set<std::tuple<int, int, int>> voxels;
  bool from_mapper = false;  // voxels from MAP_UPDATE (else from the cloud points)
  bool force_map = false;    // the source changed: the next /map goes out at once
  bool map_changed = false;
  int64_t last_map_ns = INT64_MIN;
  int64_t last_cloud_utime = 0;
  std::map<std::string, int64_t> rejected;

  std::string rootFrame() const {
    switch (kind) {
      case RigKind::kRotatingLidar:
        return "O";
      case RigKind::kMobileLidar:
        return "world";
      case RigKind::kRotatingProfile:
        return "O_r";
    }
    return "world";
  }

  void staticFrames(int64_t utime, int64_t t_ns, std::vector<FoxgloveMessage>* out);
  void cloud(const cloud_chunk_t& c, int64_t t_ns, std::vector<FoxgloveMessage>* out);
  void mapUpdate(const map_update_t& m);
  void map(int64_t t_ns, bool force, std::vector<FoxgloveMessage>* out);
  void pose(const char* topic, const pose2d_t& p, int64_t t_ns, std::vector<FoxgloveMessage>* out);
  void scan(const lidar_scan_t& s, int64_t t_ns, std::vector<FoxgloveMessage>* out);
  void profile(const profile_t& p, int64_t t_ns, std::vector<FoxgloveMessage>* out);
  void status(const process_status_t& s, int64_t t_ns, std::vector<FoxgloveMessage>* out);
};

FoxgloveConverter::FoxgloveConverter(const Rig& rig) : state_(std::make_unique<State>()) {
  state_->kind = rig.kind();
  std::visit(
      [this](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        state_->resolution_m = c.mapper.resolution_m;
        if constexpr (std::is_same_v<T, RotatingLidarConfig>) {
          state_->lidar_offset_x_m = c.geometry.lidar_offset_x_mm * 1e-3;
        } else if constexpr (std::is_same_v<T, MobileLidarConfig>) {
          state_->T_body_lidar = c.mounting.toMounting().T_BL();
          state_->lidar_time_offset_us = c.assembler.lidarTimeOffsetUs();
        } else {
          state_->profile_geometry = c.geometry.toGeometry();
        }
      },
      rig.config);
}

FoxgloveConverter::~FoxgloveConverter() = default;

const std::map<std::string, int64_t>& FoxgloveConverter::rejected() const {
  return state_->rejected;
}

void FoxgloveConverter::State::staticFrames(int64_t utime, int64_t t_ns,
                                            std::vector<FoxgloveMessage>* out) {
  static_sent = true;
  if (kind == RigKind::kRotatingLidar) {
    out->push_back(frameTransform("O", "O'", Eigen::Isometry3d::Identity(), utime, t_ns));
    out->push_back(
        frameTransform("O'", "L", rotationZ(0.0, {lidar_offset_x_m, 0, 0}), utime, t_ns));
  } else if (kind == RigKind::kMobileLidar) {
    out->push_back(frameTransform("world", "body", Eigen::Isometry3d::Identity(), utime, t_ns));
    out->push_back(frameTransform("body", "L", T_body_lidar, utime, t_ns));
  } else {
    const SensorPose s = sensorPoseInRigFrame(profile_geometry, 0.0);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear().col(0) = s.y_axis.cross(s.z_axis).normalized();
    T.linear().col(1) = s.y_axis.normalized();
    T.linear().col(2) = s.z_axis.normalized();
    T.translation() = s.origin * 1e-3;
    out->push_back(frameTransform("O_r", "S", T, utime, t_ns));
  }
}

void FoxgloveConverter::State::cloud(const cloud_chunk_t& c, int64_t t_ns,
                                     std::vector<FoxgloveMessage>* out) {
  // validateChunk: nintensities is 0 or npoints.
  const bool with_intensity = c.nintensities > 0 && c.intensities.size() == c.xyz_m.size();
  std::vector<float> values;
  values.reserve(c.xyz_m.size() * (with_intensity ? 4 : 3));
  for (size_t i = 0; i < c.xyz_m.size(); ++i) {
    const auto& p = c.xyz_m[i];
    values.insert(values.end(), {p[0], p[1], p[2]});
    if (with_intensity) values.push_back(c.intensities[i]);
    if (from_mapper || !std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      continue;
    voxels.emplace(static_cast<int>(std::floor(p[0] / resolution_m)),
                   static_cast<int>(std::floor(p[1] / resolution_m)),
                   static_cast<int>(std::floor(p[2] / resolution_m)));
  }
  map_changed = map_changed || (!from_mapper && !c.xyz_m.empty());
  last_cloud_utime = c.utime;
  // Rig A: a corrected chunk is in O, rotated by phi_offset about Z from O' (Eq. 8-10).
  if (kind == RigKind::kRotatingLidar && c.phi_offset_rad != last_phi_offset) {
    last_phi_offset = c.phi_offset_rad;
    out->push_back(frameTransform("O", "O'", rotationZ(finite(c.phi_offset_rad)), c.utime, t_ns));
  }
  out->push_back(
      message("/sweep_cloud", kPointCloud,
              pointCloudJson(c.utime, c.frame,
                             with_intensity ? std::vector<std::string>{"x", "y", "z", "intensity"}
                                            : std::vector<std::string>{"x", "y", "z"},
                             values),
              t_ns));
}

// The mapper's own voxels: from the first MAP_UPDATE on, the cloud-derived ones are dropped and
// the set follows the updates (validated by the caller).
void FoxgloveConverter::State::mapUpdate(const map_update_t& m) {
  if (!from_mapper) {
    voxels.clear();
    force_map = true;
  }
  from_mapper = true;
  if (m.full && m.chunk_index == 0) voxels.clear();  // its chunks list every occupied voxel
  resolution_m = m.resolution_m;
  for (const auto& v : m.occupied) voxels.emplace(v[0], v[1], v[2]);
  for (const auto& v : m.freed) voxels.erase({v[0], v[1], v[2]});
  map_changed = true;
  last_cloud_utime = m.utime;
}

void FoxgloveConverter::State::map(int64_t t_ns, bool force, std::vector<FoxgloveMessage>* out) {
  // INT64_MIN: no map sent yet (the difference would overflow).
  force = force || force_map;
  if (!map_changed || (!force && last_map_ns != INT64_MIN && t_ns - last_map_ns < kMapPeriodNs))
    return;
  force_map = false;
  std::vector<float> values;
  values.reserve(voxels.size() * 3);
  for (const auto& [i, j, k] : voxels) {  // voxel centres, in key order (deterministic)
    values.insert(values.end(), {static_cast<float>((i + 0.5) * resolution_m),
                                 static_cast<float>((j + 0.5) * resolution_m),
                                 static_cast<float>((k + 0.5) * resolution_m)});
  }
  out->push_back(message("/map", kPointCloud,
                         pointCloudJson(last_cloud_utime, rootFrame(), {"x", "y", "z"}, values),
                         t_ns));
  map_changed = false;
  last_map_ns = t_ns;
}

void FoxgloveConverter::State::pose(const char* topic, const pose2d_t& p, int64_t t_ns,
                                    std::vector<FoxgloveMessage>* out) {
  const Eigen::Isometry3d T = rotationZ(finite(p.theta_rad), {p.x_m, p.y_m, 0.0});
  out->push_back(message(
      topic, kPoseInFrame,
      json{{"timestamp", timeJson(p.utime)}, {"frame_id", "world"}, {"pose", poseJson(T)}}, t_ns));
  if (std::strcmp(topic, "/pose") == 0) {
    out->push_back(frameTransform("world", "body", T, p.utime, t_ns));
  }
}

void FoxgloveConverter::State::scan(const lidar_scan_t& s, int64_t t_ns,
                                    std::vector<FoxgloveMessage>* out) {
  const bool have_intensity = s.nintensities == s.nranges && s.nranges > 0;
  if (s.nangles == s.nranges && s.nangles > 0) {  // uneven: points in L
    std::vector<float> values;
    values.reserve(s.ranges_m.size() * 4);
    for (int i = 0; i < s.nranges; ++i) {
      const float r = s.ranges_m[i], a = s.angles_rad[i];
      if (!(r > 0.0f) || !std::isfinite(r)) continue;
      values.insert(values.end(), {0.0f, r * std::sin(a), r * std::cos(a),
                                   have_intensity ? s.intensities[i] : 0.0f});
    }
    out->push_back(message(
        "/lidar_points", kPointCloud,
        pointCloudJson(s.utime - lidar_time_offset_us, "L", {"x", "y", "z", "intensity"}, values),
        t_ns));
    return;
  }
  json ranges = json::array(), intensities = json::array();
  for (int i = 0; i < s.nranges; ++i) {
    ranges.push_back(finite(s.ranges_m[i]));
    if (have_intensity) intensities.push_back(finite(s.intensities[i]));
  }
  const double end = s.angle_min_rad + s.angle_increment_rad * std::max(s.nranges - 1, 0);
  json j = {{"timestamp", timeJson(s.utime - lidar_time_offset_us)},
            {"frame_id", "L"},
            {"pose", poseJson(laserScanPoseInL())},
            {"start_angle", finite(s.angle_min_rad)},
            {"end_angle", finite(end)},
            {"ranges", ranges},
            {"intensities", intensities}};
  out->push_back(message("/lidar_scan", kLaserScan, j, t_ns));
}

void FoxgloveConverter::State::profile(const profile_t& p, int64_t t_ns,
                                       std::vector<FoxgloveMessage>* out) {
  const double angle = turntableAngleRad(p.encoder_counts, p.counts_per_revolution, 0.0);
  const SensorPose s = sensorPoseInRigFrame(profile_geometry, angle);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = s.y_axis.cross(s.z_axis).normalized();
  T.linear().col(1) = s.y_axis.normalized();
  T.linear().col(2) = s.z_axis.normalized();
  T.translation() = s.origin * 1e-3;
  out->push_back(frameTransform("O_r", "S", T, p.utime, t_ns));
  std::vector<float> values;
  values.reserve(p.y_mm.size() * 3);
  for (size_t i = 0; i < p.y_mm.size() && i < p.z_mm.size(); ++i) {
    values.insert(values.end(), {0.0f, p.y_mm[i] * 1e-3f, p.z_mm[i] * 1e-3f});
  }
  out->push_back(message("/profile", kPointCloud,
                         pointCloudJson(p.utime, "S", {"x", "y", "z"}, values), t_ns));
}

void FoxgloveConverter::State::status(const process_status_t& s, int64_t t_ns,
                                      std::vector<FoxgloveMessage>* out) {
  // foxglove.Log levels: 2 INFO, 3 WARNING, 4 ERROR.
  const int level = s.health == process_status_t::OK         ? 2
                    : s.health == process_status_t::DEGRADED ? 3
                                                             : 4;
  std::string text = s.health == process_status_t::OK         ? "OK"
                     : s.health == process_status_t::DEGRADED ? "DEGRADED"
                                                              : "FAILED";
  if (!s.detail.empty()) text += ": " + s.detail;
  for (int i = 0; i < s.ncounters && i < static_cast<int>(s.counter_values.size()); ++i) {
    text +=
        (i == 0 ? " | " : ", ") + s.counter_names[i] + "=" + std::to_string(s.counter_values[i]);
  }
  json j = {{"timestamp", timeJson(s.utime)},
            {"level", level},
            {"message", text},
            {"name", s.process},
            {"file", ""},
            {"line", 0}};
  out->push_back(message("/status", kLog, j, t_ns));
}

namespace {

// Decodes `size` bytes as a T; false (and counted in `rejected`) when they are not one.
template <class T>
bool decode(const std::string& channel, const void* data, std::size_t size, T* msg,
            std::map<std::string, int64_t>* rejected) {
  if (decodeMessage(static_cast<const uint8_t*>(data), size, msg)) return true;
  ++(*rejected)[channel];
  return false;
}

}  // namespace

std::vector<FoxgloveMessage> FoxgloveConverter::convert(const std::string& channel,
                                                        const void* data, std::size_t size,
                                                        int64_t log_time_ns) {
  std::vector<FoxgloveMessage> out;
  State& s = *state_;
  if (!s.static_sent) s.staticFrames(log_time_ns / 1000, log_time_ns, &out);
  auto& rejected = s.rejected;
  namespace ch = channels;
  if (channel == ch::kSweepCloud) {
    cloud_chunk_t m;
    if (decode(channel, data, size, &m, &rejected)) {
      if (validateChunk(m).empty()) {
        s.cloud(m, log_time_ns, &out);
      } else {
        ++rejected[channel];
      }
    }
  } else if (channel == ch::kMapUpdate) {
    map_update_t m;
    if (decode(channel, data, size, &m, &rejected)) {
      if (validateMapUpdate(m).empty()) {
        s.mapUpdate(m);
        if (m.chunk_index == m.chunk_count - 1) s.map(log_time_ns, false, &out);  // update done
      } else {
        ++rejected[channel];
      }
    }
  } else if (channel == ch::kSweepStatus || channel == ch::kMapStats) {
    s.map(log_time_ns, false, &out);
  } else if (channel == ch::kOdometryPose || channel == ch::kWheelOdometry ||
             channel == ch::kTruthPose) {
    pose2d_t m;
    const char* topic = channel == ch::kOdometryPose    ? "/pose"
                        : channel == ch::kWheelOdometry ? "/wheel_odometry"
                                                        : "/truth_pose";
    if (decode(channel, data, size, &m, &rejected)) s.pose(topic, m, log_time_ns, &out);
  } else if (channel == ch::kMotorState && s.kind == RigKind::kRotatingLidar) {
    motor_state_t m;
    if (decode(channel, data, size, &m, &rejected)) {
      out.push_back(frameTransform("O'", "L",
                                   rotationZ(finite(m.commanded_angle_rad),
                                             rotationZ(finite(m.commanded_angle_rad)).linear() *
                                                 Eigen::Vector3d(s.lidar_offset_x_m, 0, 0)),
                                   m.utime, log_time_ns));
    }
  } else if (channel == ch::kLidarScan) {
    lidar_scan_t m;
    if (decode(channel, data, size, &m, &rejected)) s.scan(m, log_time_ns, &out);
  } else if (channel == ch::kProfile) {
    profile_t m;
    if (decode(channel, data, size, &m, &rejected)) {
      if (validateProfile(m).empty()) {
        s.profile(m, log_time_ns, &out);
      } else {
        ++rejected[channel];
      }
    }
  } else if (channel.rfind("STATUS_", 0) == 0) {
    process_status_t m;
    if (decode(channel, data, size, &m, &rejected)) s.status(m, log_time_ns, &out);
  }
  return out;
}

std::vector<FoxgloveMessage> FoxgloveConverter::finish(int64_t log_time_ns) {
  std::vector<FoxgloveMessage> out;
  state_->map(log_time_ns, true, &out);
  return out;
}

}  // namespace sweepmap::viz
