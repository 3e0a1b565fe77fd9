// Rig kind `rotating_profile` (rig C, Zhao 2021): a line-structured-light profile sensor
// turned by a turntable with an encoder; its origin sits at offsets (M, N) from the axis
// (core/profile_geometry.hpp). One strictly loaded YAML file (config/rig_c.yaml).
#pragma once

#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/profile_geometry.hpp"
#include "core/rig_components.hpp"
#include "sim/profiler.hpp"

namespace sweepmap {

// The axis offsets the assembler and the calibration start from: nominal values, or the
// calibrated ones from `calibration_file`.
struct ProfileGeometryConfig {
  double offset_m_mm = 120.0;  // M: axis to laser plane, along X_r
  double offset_n_mm = 412.0;  // N: foot of the perpendicular to the sensor's origin
  double laser_tilt_deg = 0.0;
  double encoder_zero_deg = 0.0;
  // A calibration YAML (relative to the rig file; "" = none) whose axis_offset.* replace the
  // four values above (what `sweepmap calib axis-offset` writes).
  std::string calibration_file;
  void declare(ConfigSchema& s, const std::string& prefix);
  ProfileGeometry toGeometry() const;
};

struct RotatingProfileConfig {
  std::string rig = "rotating_profile";  // the kind, checked on load
  ProfilerConfig profiler;
  TurntableConfig turntable;
  ProfileGeometryConfig geometry;
  MapperConfig mapper;    // sweepmap-mapper: the OctoMap of the profiles (one ray cast each)
  NetworkConfig network;  // every live process: its receive queue and datagram reassembly
  SimProfileConfig sim;   // `sweepmap sim` only: the truth and the error sources
  void declare(ConfigSchema& s);
};

// Loads a rig file strictly (its `rig` key must say rotating_profile), then applies
// `key=value` overrides; an axis-offset calibration file the rig names replaces the
// geometry. Throws ConfigError naming the file and the key.
RotatingProfileConfig loadRotatingProfileConfig(const std::string& path,
                                                const std::vector<std::string>& overrides = {});

}  // namespace sweepmap
