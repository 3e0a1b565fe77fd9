#include "rigs/rotating_profile.hpp"

#include <cmath>
#include <filesystem>

#include "core/calibration_file.hpp"
#include "rigs/rig_kind.hpp"

namespace sweepmap {

void ProfileGeometryConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "offset_m_mm", &offset_m_mm, "mm",
        "M: the turntable axis to the laser plane, along X_r (Zhao 2021 Eq. 2)");
  s.add(p + "offset_n_mm", &offset_n_mm, "mm",
        "N: the foot of that perpendicular to the sensor's origin, along the profile's y (Eq. 1)");
  s.add(p + "laser_tilt_deg", &laser_tilt_deg, "deg",
        "tilt of the laser plane from the axis, about the sensor's y (0 in Eq. 7)");
  s.add(p + "encoder_zero_deg", &encoder_zero_deg, "deg", "turntable angle at encoder count 0");
  s.add(p + "calibration_file", &calibration_file, "",
        "calibration YAML (relative to the rig file) whose axis_offset.* replace the four values "
        "above; \"\" = none (sweepmap calib axis-offset writes it)");
}

ProfileGeometry ProfileGeometryConfig::toGeometry() const {
  return {offset_m_mm, offset_n_mm, laser_tilt_deg * M_PI / 180.0, encoder_zero_deg * M_PI / 180.0};
}

void RotatingProfileConfig::declare(ConfigSchema& s) {
  s.add("rig", &rig, "",
        "rig kind: rotating_profile (a line-structured-light profile sensor on a turntable, "
        "Zhao 2021)");
  profiler.declare(s, "profiler.");
  turntable.declare(s, "turntable.");
  geometry.declare(s, "geometry.");
  mapper.declare(s, "mapper.");
  s.add("mapper.batch_s", &mapper.batch_s, "s",
        "profiles whose time falls in the same window of this length are inserted as one batch "
        "(one update of the tree's inner nodes and one MAP_STATS; the map is the same); 0: "
        "every profile on its own");
  network.declare(s, "network.");
  sim.declare(s, "sim.");
}

namespace {

void validate(const std::string& path, const RotatingProfileConfig& rig) {
  const auto require = [&](bool ok, const char* key, const char* what) {
    if (!ok) throw ConfigError(path + ": key '" + key + "' " + what);
  };
  const ProfilerConfig& p = rig.profiler;
  require(p.column_count > 0 && p.column_count <= 4096, "profiler.column_count",
          "must be 1..4096 (one profile per UDP datagram)");
  require(p.near_mm > 0 && p.far_mm > p.near_mm, "profiler.far_mm", "must exceed near_mm > 0");
  require(p.fov_far_mm > 0, "profiler.fov_far_mm", "must be > 0");
  require(p.profile_rate_hz > 0, "profiler.profile_rate_hz", "must be > 0");
  require(p.device == "sim", "profiler.device", "must be sim (no real profile sensor driver yet)");
  const TurntableConfig& t = rig.turntable;
  require(t.counts_per_revolution > 0, "turntable.counts_per_revolution", "must be > 0");
  require(t.speed_deg_s > 0, "turntable.speed_deg_s", "must be > 0");
  require(t.sweep_end_deg != t.sweep_start_deg, "turntable.sweep_end_deg",
          "must differ from sweep_start_deg");
  require(t.device == "sim", "turntable.device", "must be sim (no real turntable driver yet)");
  // A level face has no azimuth: its normal must lean visibly.
  require(t.reference.normal_tilt_deg >= 5 && t.reference.normal_tilt_deg < 80,
          "turntable.reference.normal_tilt_deg",
          "must be in [5, 80) (a level face has no azimuth)");
  require(t.reference.azimuth_sigma_deg >= 0, "turntable.reference.azimuth_sigma_deg",
          "must be >= 0");
  require(rig.mapper.resolution_m >= 0.0005, "mapper.resolution_m", "must be >= 0.0005");
  require(rig.mapper.batch_s >= 0.0 && rig.mapper.batch_s <= 3600.0, "mapper.batch_s",
          "must be in [0, 3600]");
  rig.mapper.validateBounds(path, "mapper.");
  rig.network.validate(path, "network.");
  const SimProfileConfig& s = rig.sim;
  require(s.scene == "plate" || s.scene == "test_piece", "sim.scene",
          "must be plate or test_piece");
  require(s.plate_count >= 1, "sim.plate_count", "must be >= 1");
  require(s.plate_size_mm > 0, "sim.plate_size_mm", "must be > 0");
  require(s.range_noise_sigma_mm >= 0, "sim.range_noise_sigma_mm", "must be >= 0");
  require(s.encoder_noise_counts >= 0, "sim.encoder_noise_counts", "must be >= 0");
  require(std::fabs(s.plate_tilt_deg) < 80, "sim.plate_tilt_deg", "must be within +-80");
  require(s.pause_s >= 0, "sim.pause_s", "must be >= 0");
}

}  // namespace

RotatingProfileConfig loadRotatingProfileConfig(const std::string& path,
                                                const std::vector<std::string>& overrides) {
  RotatingProfileConfig rig;
  ConfigSchema schema;
  loadRigSchema(path, overrides, "rotating_profile", &rig, &schema);
  if (!rig.geometry.calibration_file.empty()) {
    const AxisOffsetCalibration c =
        loadFileBesideRig(path, "geometry.calibration_file", rig.geometry.calibration_file,
                          loadAxisOffsetCalibration);
    rig.geometry.offset_m_mm = c.m_mm;
    rig.geometry.offset_n_mm = c.n_mm;
    rig.geometry.laser_tilt_deg = c.laser_tilt_deg;
    rig.geometry.encoder_zero_deg = c.encoder_zero_deg;
  }
  validate(path, rig);
  return rig;
}

}  // namespace sweepmap
