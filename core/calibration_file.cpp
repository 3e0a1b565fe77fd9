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

// The keys of `section` in the file (any; for a rig calibration file).
std::vector<std::string> sectionKeys(const std::string& path, const std::string& section) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot open calibration file");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  std::vector<std::string> keys;
  if (root.IsMap() && root[section] && root[section].IsMap()) {
    for (const auto& kv : root[section]) keys.push_back(kv.first.as<std::string>());
  }
  if (keys.empty()) throw ConfigError(path + ": missing key '" + section + "'");
  return keys;
}

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

// What one kind of calibration file adds to the common part: the comment line at its top, its
// section and the section's keys, each bound to a member of the kind's struct (every kind has
// `source` and `logs` too, the common provenance).
template <class Calibration>
struct CalibrationKind {
  const char* header;
  const char* section;
  std::vector<std::pair<const char*, double Calibration::*>> keys;

  Calibration load(const std::string& path) const {
    std::vector<std::string> names;
    for (const auto& [name, member] : keys) names.emplace_back(name);
    const CalibrationFileContent f = loadCalibrationFile(path, section, names);
    Calibration c;
    for (const auto& [name, member] : keys) c.*member = f.values.at(name);
    c.source = f.source;
    c.logs = f.logs;
    return c;
  }

  void write(const std::string& path, const Calibration& c) const {
    std::vector<std::pair<std::string, double>> values;
    for (const auto& [name, member] : keys) values.emplace_back(name, c.*member);
    writeCalibrationFile(path, header, section, values, c.source, c.logs);
  }
};

const CalibrationKind<PlateCalibration> kPlate{
    "Plate-angle calibration (Yuan 2021 Algorithm A1); read via plate.calibration_file",
    "plate",
    {{"alpha_deg", &PlateCalibration::alpha_deg}}};

const CalibrationKind<MountingCalibration> kMounting{
    "Lidar mounting calibration (Miao 2022 section 4.2); read via mounting.calibration_file",
    "mounting",
    {{"gamma_rad", &MountingCalibration::gamma_rad},
     {"beta_rad", &MountingCalibration::beta_rad},
     {"alpha_rad", &MountingCalibration::alpha_rad}}};

const CalibrationKind<AxisOffsetCalibration> kAxisOffset{
    "Axis-offset calibration of a rotating profile sensor (Zhao 2021, plane constraints); read "
    "via geometry.calibration_file",
    "axis_offset",
    {{"m_mm", &AxisOffsetCalibration::m_mm},
     {"n_mm", &AxisOffsetCalibration::n_mm},
     {"laser_tilt_deg", &AxisOffsetCalibration::laser_tilt_deg},
     {"encoder_zero_deg", &AxisOffsetCalibration::encoder_zero_deg}}};

const CalibrationKind<LidarOffsetCalibration> kLidarOffset{
    "Lidar-to-axis offset of a rotating 2D lidar (t_L^O', plane constraints); read via "
    "geometry.calibration_file",
    "geometry",
    {{"lidar_offset_x_mm", &LidarOffsetCalibration::lidar_offset_x_mm}}};

const char* const kRigCalibrationHeader =
    "Rig calibration (sweepmap calib rig): rig-file keys, applied over the rig file's own by "
    "its calibration_file key";

}  // namespace

RigCalibrationFile loadRigCalibration(const std::string& path) {
  const std::vector<std::string> keys = sectionKeys(path, "parameters");
  const CalibrationFileContent f = loadCalibrationFile(path, "parameters", keys);
  RigCalibrationFile c;
  for (const auto& k : keys) c.parameters.emplace_back(k, f.values.at(k));
  c.source = f.source;
  c.logs = f.logs;
  return c;
}

void writeRigCalibration(const std::string& path, const RigCalibrationFile& c) {
  writeCalibrationFile(path, kRigCalibrationHeader, "parameters", c.parameters, c.source, c.logs);
}

PlateCalibration loadPlateCalibration(const std::string& path) { return kPlate.load(path); }
void writePlateCalibration(const std::string& path, const PlateCalibration& c) {
  kPlate.write(path, c);
}

MountingCalibration loadMountingCalibration(const std::string& path) {
  return kMounting.load(path);
}
void writeMountingCalibration(const std::string& path, const MountingCalibration& c) {
  kMounting.write(path, c);
}

AxisOffsetCalibration loadAxisOffsetCalibration(const std::string& path) {
  return kAxisOffset.load(path);
}
void writeAxisOffsetCalibration(const std::string& path, const AxisOffsetCalibration& c) {
  kAxisOffset.write(path, c);
}

LidarOffsetCalibration loadLidarOffsetCalibration(const std::string& path) {
  return kLidarOffset.load(path);
}
void writeLidarOffsetCalibration(const std::string& path, const LidarOffsetCalibration& c) {
  kLidarOffset.write(path, c);
}

}  // namespace sweepmap
