#include "processes/convert.hpp"

#include <algorithm>
#include <cmath>

namespace sweepmap {

namespace {

template <class To, class From>
void assign(To* to, const From& from) {
  *to = static_cast<To>(from);
}

// The fields Scan2D and lidar_scan_t share by name, either way (the message is float where the
// struct is double).
template <class From, class To>
void copyScanFields(const From& f, To* t) {
  assign(&t->utime, f.utime);
  assign(&t->seq, f.seq);
  assign(&t->angle_min_rad, f.angle_min_rad);
  assign(&t->angle_increment_rad, f.angle_increment_rad);
  assign(&t->time_increment_ns, f.time_increment_ns);
  assign(&t->range_min_m, f.range_min_m);
  assign(&t->range_max_m, f.range_max_m);
  t->ranges_m = f.ranges_m;
  t->device_stamp = f.device_stamp;
  t->intensities = f.intensities;
  t->angles_rad = f.angles_rad;
}

// The fields Profile and profile_t share by name (all of the struct's), either way.
template <class From, class To>
void copyProfileFields(const From& f, To* t) {
  t->utime = f.utime;
  t->sequence = f.sequence;
  t->sweep_id = f.sweep_id;
  t->encoder_counts = f.encoder_counts;
  t->counts_per_revolution = f.counts_per_revolution;
  t->column_count = f.column_count;
  t->column = f.column;
  t->y_mm = f.y_mm;
  t->z_mm = f.z_mm;
}

}  // namespace

lidar_scan_t toLcm(const Scan2D& scan) {
  lidar_scan_t m;
  copyScanFields(scan, &m);
  m.nranges = static_cast<int32_t>(scan.ranges_m.size());
  m.nintensities = static_cast<int32_t>(scan.intensities.size());
  m.nangles = static_cast<int32_t>(scan.angles_rad.size());
  return m;
}

Scan2D fromLcm(const lidar_scan_t& m) {
  Scan2D s;
  copyScanFields(m, &s);
  return s;
}

std::string validateWindow(const scan_window_t& m) {
  if (m.end_utime <= m.start_utime) return "window ends before it starts";
  if (m.end_utime - m.start_utime > 600LL * 1000000) return "window longer than 10 minutes";
  if (!std::isfinite(m.angular_velocity_rad_s) || m.angular_velocity_rad_s == 0.0) {
    return "bad angular velocity";
  }
  if (!std::isfinite(m.sweep_angle_rad)) return "bad sweep angle";
  return {};
}

SweepWindow fromLcm(const scan_window_t& m) {
  SweepWindow w;
  w.sweep_id = m.sweep_id;
  w.mode = m.mode;
  w.start_utime = m.start_utime;
  w.end_utime = m.end_utime;
  w.omega_rad_s = m.angular_velocity_rad_s;
  w.accel_overlap = m.accel_overlap;
  return w;
}

std::vector<cloud_chunk_t> toChunks(const AssembledSweep& sweep, int chunk_points) {
  const size_t n = sweep.points.size();
  const size_t per = static_cast<size_t>(std::max(1, chunk_points));
  const int count = static_cast<int>(std::max<size_t>(1, (n + per - 1) / per));
  std::vector<cloud_chunk_t> chunks;
  chunks.reserve(static_cast<size_t>(count));
  for (int c = 0; c < count; ++c) {
    cloud_chunk_t m;
    m.utime = sweep.window.start_utime;
    m.sweep_id = sweep.window.sweep_id;
    m.mode = sweep.window.mode;
    m.chunk_index = c;
    m.chunk_count = count;
    m.total_points = static_cast<int32_t>(n);
    m.frame = sweep.corrected ? "O" : "O'";
    m.corrected = sweep.corrected;
    m.phi_offset_rad = sweep.phi_offset_rad;
    m.sensor_origin_m[0] = m.sensor_origin_m[1] = m.sensor_origin_m[2] = 0.0;  // on the axis
    const size_t begin = static_cast<size_t>(c) * per;
    const size_t end = std::min(n, begin + per);
    m.npoints = static_cast<int32_t>(end > begin ? end - begin : 0);
    m.xyz_m.resize(static_cast<size_t>(m.npoints));
    for (size_t i = begin; i < end; ++i) {
      const auto& p = sweep.points[i];
      m.xyz_m[i - begin] = {p.x(), p.y(), p.z()};
    }
    if (sweep.intensities.size() == n) {  // else the lidar measures none: 0 intensities
      m.intensities.assign(sweep.intensities.begin() + static_cast<std::ptrdiff_t>(begin),
                           sweep.intensities.begin() + static_cast<std::ptrdiff_t>(end));
    }
    m.nintensities = static_cast<int32_t>(m.intensities.size());
    chunks.push_back(std::move(m));
  }
  return chunks;
}

sweep_status_t toStatus(const AssembledSweep& sweep, int chunk_count) {
  sweep_status_t s;
  s.utime = sweep.window.start_utime;
  s.sweep_id = sweep.window.sweep_id;
  s.mode = sweep.window.mode;
  s.scans = sweep.scans;
  s.points = static_cast<int32_t>(sweep.points.size());
  s.plate_points = sweep.plate.points;
  s.beta_rad = sweep.plate.found ? sweep.plate.beta_rad : std::nan("");
  s.alpha_rad = sweep.alpha_rad;
  s.phi_offset_rad = sweep.phi_offset_rad;
  s.corrected = sweep.corrected;
  s.reason = sweep.reason;
  s.chunk_count = chunk_count;
  return s;
}

std::string validateChunk(const cloud_chunk_t& m) {
  if (m.chunk_count <= 0 || m.chunk_index < 0 || m.chunk_index >= m.chunk_count) {
    return "bad chunk index " + std::to_string(m.chunk_index) + " of " +
           std::to_string(m.chunk_count);
  }
  if (m.total_points < m.npoints) return "chunk has more points than its sweep";
  for (const double o : m.sensor_origin_m) {
    if (!std::isfinite(o) || std::abs(o) > 1e4) return "sensor origin not finite or beyond 10 km";
  }
  for (const auto& p : m.xyz_m) {
    if (p.size() != 3 || !std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      return "non-finite point";
    }
  }
  if (m.nintensities != 0 && m.nintensities != m.npoints) {
    return "nintensities " + std::to_string(m.nintensities) + " is neither 0 nor npoints " +
           std::to_string(m.npoints);
  }
  return {};
}

std::vector<map_update_t> toMapUpdates(const std::vector<std::array<int32_t, 3>>& occupied,
                                       const std::vector<std::array<int32_t, 3>>& freed,
                                       const map_update_t& header, int chunk_voxels) {
  const size_t per = static_cast<size_t>(std::max(1, chunk_voxels));
  const size_t n_occupied = occupied.size(), n = n_occupied + freed.size();
  const int count = static_cast<int>(std::max<size_t>(1, (n + per - 1) / per));
  std::vector<map_update_t> chunks;
  chunks.reserve(static_cast<size_t>(count));
  for (int c = 0; c < count; ++c) {
    map_update_t m = header;
    m.chunk_index = c;
    m.chunk_count = count;
    m.total_occupied = static_cast<int32_t>(n_occupied);
    m.total_freed = static_cast<int32_t>(freed.size());
    m.occupied.clear();
    m.freed.clear();
    const size_t begin = static_cast<size_t>(c) * per, end = std::min(n, begin + per);
    for (size_t i = begin; i < end; ++i) {
      if (i < n_occupied) {
        const auto& v = occupied[i];
        m.occupied.push_back({v[0], v[1], v[2]});
      } else {
        const auto& v = freed[i - n_occupied];
        m.freed.push_back({v[0], v[1], v[2]});
      }
    }
    m.noccupied = static_cast<int32_t>(m.occupied.size());
    m.nfreed = static_cast<int32_t>(m.freed.size());
    chunks.push_back(std::move(m));
  }
  return chunks;
}

namespace {

// Empty when every index of `voxels` lies inside OctoMap's key range, else the reason.
std::string checkIndices(const std::vector<std::vector<int32_t>>& voxels, const char* list) {
  for (size_t i = 0; i < voxels.size(); ++i) {
    if (voxels[i].size() != 3)
      return std::string(list) + " voxel " + std::to_string(i) + ": not 3 indices";
    for (const int32_t v : voxels[i]) {
      if (v < -32768 || v > 32767) {
        return std::string(list) + " voxel " + std::to_string(i) + ": index " + std::to_string(v) +
               " outside -32768..32767";
      }
    }
  }
  return {};
}

}  // namespace

std::string validateMapUpdate(const map_update_t& m) {
  if (m.seq < 1) return "seq " + std::to_string(m.seq) + " is not >= 1";
  if (m.chunk_count <= 0 || m.chunk_index < 0 || m.chunk_index >= m.chunk_count) {
    return "bad chunk index " + std::to_string(m.chunk_index) + " of " +
           std::to_string(m.chunk_count);
  }
  if (m.noccupied < 0 || m.nfreed < 0 || m.occupied.size() != static_cast<size_t>(m.noccupied) ||
      m.freed.size() != static_cast<size_t>(m.nfreed)) {
    return "noccupied " + std::to_string(m.noccupied) + " / nfreed " + std::to_string(m.nfreed) +
           " do not match their arrays";
  }
  if (m.full && m.total_freed != 0) return "a full update frees voxels";
  if (m.noccupied > m.total_occupied || m.nfreed > m.total_freed) {
    return "a chunk holds more voxels than its update";
  }
  if (int64_t{m.noccupied} + m.nfreed > kMapUpdateChunkVoxels) {
    return "more than " + std::to_string(kMapUpdateChunkVoxels) + " voxels in one chunk";
  }
  if (!std::isfinite(m.resolution_m) || !(m.resolution_m > 0.0)) {
    return "resolution_m is not a finite number > 0";
  }
  if (m.occupied_voxels < 0) return "occupied_voxels is negative";
  if (std::string why = checkIndices(m.occupied, "occupied"); !why.empty()) return why;
  return checkIndices(m.freed, "freed");
}

truth_shaft_t toLcm(const ShaftSegment& s, int64_t utime) {
  truth_shaft_t m;
  m.utime = utime;
  m.start_utime = s.start_utime;
  m.angle_rad = s.angle_rad;
  m.velocity_rad_s = s.velocity_rad_s;
  m.accel_rad_s2 = s.accel_rad_s2;
  return m;
}

ShaftSegment fromLcm(const truth_shaft_t& m) {
  return {m.start_utime, m.angle_rad, m.velocity_rad_s, m.accel_rad_s2};
}

imu_t toLcm(const ImuSample& s) {
  imu_t m{};
  m.utime = s.utime;
  for (int k = 0; k < 3; ++k) {
    m.gyro_rad_s[k] = s.gyro[k];
    m.accel_m_s2[k] = s.accel[k];
    m.rpy_rad[k] = s.rpy[k];
  }
  return m;
}

wheel_ticks_t toLcm(const WheelTicks& t) {
  wheel_ticks_t m{};
  m.utime = t.utime;
  m.left_ticks = t.left;
  m.right_ticks = t.right;
  return m;
}

profile_t toLcm(const Profile& p) {
  profile_t m;
  copyProfileFields(p, &m);
  m.point_count = static_cast<int32_t>(p.column.size());
  return m;
}

Profile fromLcm(const profile_t& m) {
  Profile p;
  copyProfileFields(m, &p);
  return p;
}

std::string validateProfile(const profile_t& m) {
  const auto n = static_cast<size_t>(std::max(0, m.point_count));
  if (m.point_count < 0 || m.column.size() != n || m.y_mm.size() != n || m.z_mm.size() != n) {
    return "point_count " + std::to_string(m.point_count) + " does not match its arrays";
  }
  if (m.counts_per_revolution <= 0) {
    return "counts_per_revolution " + std::to_string(m.counts_per_revolution) + " is not > 0";
  }
  if (m.point_count > m.column_count) return "more points than the sensor's columns";
  for (size_t i = 0; i < n; ++i) {
    if (m.column[i] < 0 || m.column[i] >= m.column_count) {
      return "point " + std::to_string(i) + ": column " + std::to_string(m.column[i]) +
             " outside 0.." + std::to_string(m.column_count - 1);
    }
    if (!std::isfinite(m.y_mm[i]) || !std::isfinite(m.z_mm[i])) {
      return "point " + std::to_string(i) + " (column " + std::to_string(m.column[i]) +
             "): y or z is not finite";
    }
  }
  return "";
}

}  // namespace sweepmap
