#include "rigs/rotating_lidar.hpp"

#include <filesystem>

#include "core/calibration_file.hpp"
#include "rigs/rig_kind.hpp"

namespace sweepmap {

void RotatingLidarConfig::declare(ConfigSchema& s) {
  s.add("rig", &rig, "", "rig kind: rotating_lidar (a 2D lidar turned by a stepper, Yuan 2021)");
  s.add("calibration_file", &calibration_file, "",
        "calibration YAML (relative to the rig file) of sweepmap calib rig, whose rig-file keys "
        "replace these values; empty: none");
  lidar.declare(s, "lidar.");
  motor.declare(s, "motor.");
  geometry.declare(s, "geometry.");
  plate.declare(s, "plate.");
  assembler.declare(s, "assembler.");
  mapper.declare(s, "mapper.");
  network.declare(s, "network.");
  sim.declare(s, "sim.");
}

namespace {

// The rig file's range checks (ConfigError naming `path` and the key).
void checkRotatingLidarConfig(const std::string& path, const RotatingLidarConfig& rig) {
  const auto require = [&](bool ok, const char* key, const char* what) {
    if (!ok) throw ConfigError(path + ": key '" + key + "' " + what);
  };
  rig.lidar.validate(path, "lidar.");
  rig.motor.validate(path, "motor.");
  require(rig.plate.region_inner_radius_mm >= 0 &&
              rig.plate.region_outer_radius_mm > rig.plate.region_inner_radius_mm,
          "plate.region_outer_radius_mm", "must exceed region_inner_radius_mm >= 0");
  require(rig.plate.region_thickness_mm > 0, "plate.region_thickness_mm", "must be > 0");
  require(rig.plate.min_points > 0, "plate.min_points", "must be > 0");
  require(rig.plate.range_gate_mm > 0, "plate.range_gate_mm", "must be > 0");
  // 4000 points of 16 bytes (x, y, z, intensity) and the header: 64.1 kB of LCM's 65499.
  require(rig.assembler.chunk_points > 0 && rig.assembler.chunk_points <= 4000,
          "assembler.chunk_points", "must be 1..4000 (one UDP datagram)");
  require(rig.assembler.max_pending_scans > 0, "assembler.max_pending_scans", "must be > 0");
  require(rig.mapper.resolution_m >= 0.005, "mapper.resolution_m", "must be >= 0.005");
  require(rig.mapper.max_range_m > 0 && rig.mapper.max_range_m <= 100, "mapper.max_range_m",
          "must be in (0, 100]");
  require(rig.mapper.prob_hit > 0.5 && rig.mapper.prob_hit < 1, "mapper.prob_hit",
          "must be in (0.5, 1)");
  require(rig.mapper.prob_miss > 0 && rig.mapper.prob_miss < 0.5, "mapper.prob_miss",
          "must be in (0, 0.5)");
  require(rig.mapper.clamp_min > 0 && rig.mapper.clamp_min < rig.mapper.clamp_max &&
              rig.mapper.clamp_max < 1,
          "mapper.clamp_max", "needs 0 < clamp_min < clamp_max < 1");
  rig.mapper.validateBounds(path, "mapper.");
  rig.network.validate(path, "network.");
  if (rig.plate.beta_method != "centroid" && rig.plate.beta_method != "ray_plane" &&
      rig.plate.beta_method != "model") {
    throw ConfigError(path + ": key 'plate.beta_method' must be centroid, ray_plane or model");
  }
  require(rig.plate.thickness_mm >= 0, "plate.thickness_mm", "must be >= 0");
}

}  // namespace

RotatingLidarConfig loadRotatingLidarConfig(const std::string& path,
                                            const std::vector<std::string>& overrides) {
  RotatingLidarConfig rig;
  ConfigSchema schema;
  loadRigSchema(path, overrides, "rotating_lidar", &rig, &schema);
  CalibratedKeys calibrated;
  if (!rig.calibration_file.empty())
    calibrated = applyRigCalibration(path, rig.calibration_file, overrides, &schema);
  // Calibration files are named relative to the rig file.
  if (!rig.plate.calibration_file.empty()) {
    rig.plate.alpha_deg = loadFileBesideRig(path, "plate.calibration_file",
                                            rig.plate.calibration_file, loadPlateCalibration)
                              .alpha_deg;
  }
  if (!rig.geometry.calibration_file.empty()) {
    rig.geometry.lidar_offset_x_mm =
        loadFileBesideRig(path, "geometry.calibration_file", rig.geometry.calibration_file,
                          loadLidarOffsetCalibration)
            .lidar_offset_x_mm;
  }
  checkCalibratedRig(path, calibrated, [&] { checkRotatingLidarConfig(path, rig); });
  return rig;
}

}  // namespace sweepmap
