#include "core/calibration_file.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/config.hpp"

namespace sweepmap {

namespace {

// A calibration file: one section of named finite numbers (all required, no others) and
// the free-form provenance under `source`.
struct CalibrationFileContent {
  std::map<std::string, double> values;  // key (without the section) -> value
  std::map<std::string, std::string> source;
  std::vector<std::string> logs;
};

CalibrationFileContent loadCalibrationFile(const std::string& path, const std::string& section,
                                           const std::vector<std::string>& keys) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot open calibration file");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) throw ConfigError(path + ": top level must be a map");
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (key != section && key != "source") throw ConfigError(path + ": unknown key '" + key + "'");
  }
  const YAML::Node node = root[section];
  for (const std::string& k : keys) {
    if (!node || !node.IsMap() || !node[k]) {
      throw ConfigError(path + ": missing key '" + section + "." + k + "'");
    }
  }
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
      throw ConfigError(path + ": unknown key '" + section + "." + key + "'");
    }
  }
  CalibrationFileContent c;
  for (const std::string& k : keys) {
    double v = 0.0;
    try {
      v = node[k].as<double>();
    } catch (const YAML::Exception&) {
      throw ConfigError(path + ": key '" + section + "." + k + "' is not a number");
    }
    if (!std::isfinite(v)) throw ConfigError(path + ": key '" + section + "." + k + "' not finite");
    c.values[k] = v;
  }
  if (const YAML::Node src = root["source"]; src && src.IsMap()) {
    for (const auto& kv : src) {
      const std::string key = kv.first.as<std::string>();
      if (key == "logs" && kv.second.IsSequence()) {
        for (const auto& l : kv.second) c.logs.push_back(l.as<std::string>());
      } else if (kv.second.IsScalar()) {
        c.source[key] = kv.second.as<std::string>();
      }
    }
  }
  return c;
}

// Writes `header` (a comment) and the content to `path.tmp`, then renames over `path`.
void writeCalibrationFile(const std::string& path, const std::string& header,
                          const std::string& section,
                          const std::vector<std::pair<std::string, double>>& values,
                          const std::map<std::string, std::string>& source,
                          const std::vector<std::string>& logs) {
  YAML::Emitter em;
  em << YAML::BeginMap;
  em << YAML::Key << section << YAML::Value << YAML::BeginMap;
  for (const auto& [k, v] : values) {
    std::ostringstream text;
    text << std::setprecision(12) << v;
    em << YAML::Key << k << YAML::Value << text.str();
  }
  em << YAML::EndMap;
  em << YAML::Key << "source" << YAML::Value << YAML::BeginMap;
  for (const auto& [k, v] : source) em << YAML::Key << k << YAML::Value << v;
  em << YAML::Key << "logs" << YAML::Value << YAML::BeginSeq;
  for (const auto& l : logs) em << l;
  em << YAML::EndSeq << YAML::EndMap << YAML::EndMap;

  // Written whole, fsync'ed and renamed over `path`: a reader never sees half a file.
  writeFileAtomic(path, "# " + header + "\n" + em.c_str() + "\n");
}

}  // namespace

PlateCalibration loadPlateCalibration(const std::string& path) {
  const CalibrationFileContent f = loadCalibrationFile(path, "plate", {"alpha_deg"});
  PlateCalibration c;
  c.alpha_deg = f.values.at("alpha_deg");
  c.source = f.source;
  c.logs = f.logs;
  return c;
}

void writePlateCalibration(const std::string& path, const PlateCalibration& c) {
  writeCalibrationFile(
      path, "Plate-angle calibration (Yuan 2021 Algorithm A1); read via plate.calibration_file",
      "plate", {{"alpha_deg", c.alpha_deg}}, c.source, c.logs);
}

MountingCalibration loadMountingCalibration(const std::string& path) {
  const CalibrationFileContent f =
      loadCalibrationFile(path, "mounting", {"gamma_rad", "beta_rad", "alpha_rad"});
  MountingCalibration c;
  c.gamma_rad = f.values.at("gamma_rad");
  c.beta_rad = f.values.at("beta_rad");
  c.alpha_rad = f.values.at("alpha_rad");
  c.source = f.source;
  c.logs = f.logs;
  return c;
}

void writeMountingCalibration(const std::string& path, const MountingCalibration& c) {
  writeCalibrationFile(
      path,
      "Lidar mounting calibration (Miao 2022 section 4.2); read via mounting.calibration_file",
      "mounting",
      {{"gamma_rad", c.gamma_rad}, {"beta_rad", c.beta_rad}, {"alpha_rad", c.alpha_rad}}, c.source,
      c.logs);
}

AxisOffsetCalibration loadAxisOffsetCalibration(const std::string& path) {
  const CalibrationFileContent f = loadCalibrationFile(
      path, "axis_offset", {"m_mm", "n_mm", "laser_tilt_deg", "encoder_zero_deg"});
  AxisOffsetCalibration c;
  c.m_mm = f.values.at("m_mm");
  c.n_mm = f.values.at("n_mm");
  c.laser_tilt_deg = f.values.at("laser_tilt_deg");
  c.encoder_zero_deg = f.values.at("encoder_zero_deg");
  c.source = f.source;
  c.logs = f.logs;
  return c;
}

void writeAxisOffsetCalibration(const std::string& path, const AxisOffsetCalibration& c) {
  writeCalibrationFile(path,
                       "Axis-offset calibration of a rotating profile sensor (Zhao 2021, plane "
                       "constraints); read via geometry.calibration_file",
                       "axis_offset",
                       {{"m_mm", c.m_mm},
                        {"n_mm", c.n_mm},
                        {"laser_tilt_deg", c.laser_tilt_deg},
                        {"encoder_zero_deg", c.encoder_zero_deg}},
                       c.source, c.logs);
}

LidarOffsetCalibration loadLidarOffsetCalibration(const std::string& path) {
  const CalibrationFileContent f = loadCalibrationFile(path, "geometry", {"lidar_offset_x_mm"});
  LidarOffsetCalibration c;
  c.lidar_offset_x_mm = f.values.at("lidar_offset_x_mm");
  c.source = f.source;
  c.logs = f.logs;
  return c;
}

void writeLidarOffsetCalibration(const std::string& path, const LidarOffsetCalibration& c) {
  writeCalibrationFile(path,
                       "Lidar-to-axis offset of a rotating 2D lidar (t_L^O', plane constraints); "
                       "read via geometry.calibration_file",
                       "geometry", {{"lidar_offset_x_mm", c.lidar_offset_x_mm}}, c.source, c.logs);
}

}  // namespace sweepmap
