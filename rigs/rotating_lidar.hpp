// Rig kind `rotating_lidar` (rig A, Yuan 2021): a 2D lidar turned about a vertical axis
// by an encoder-less stepper with a photoelectric home switch, its attitude corrected per
// sweep by a triangular plate. One strictly loaded YAML file (config/rig_a.yaml).
#pragma once

#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/rig_components.hpp"

namespace sweepmap {

struct RotatingLidarConfig {
  std::string rig = "rotating_lidar";  // the kind, checked on load
  // `sweepmap calib rig`'s result (relative to this file): its rig-file keys replace these
  // values; empty: none.
  std::string calibration_file;
  LidarConfig lidar;
  MotorConfig motor;
  GeometryConfig geometry;
  PlateConfig plate;
  AssemblerConfig assembler;
  MapperConfig mapper;
  NetworkConfig network;  // every live process: its receive queue and datagram reassembly
  SimRigConfig sim;
  void declare(ConfigSchema& s);
};

// Loads a rig file strictly (its `rig` key must say rotating_lidar), then applies
// `key=value` overrides; a rig calibration file (calibration_file) replaces the keys it holds, a
// plate calibration file the rig names replaces plate.alpha_deg, a
// geometry calibration file geometry.lidar_offset_x_mm.
// Throws ConfigError naming the file and the key.
RotatingLidarConfig loadRotatingLidarConfig(const std::string& path,
                                            const std::vector<std::string>& overrides = {});

}  // namespace sweepmap
