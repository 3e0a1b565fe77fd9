#include "core/calibration_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/config.hpp"

namespace sweepmap {

PlateCalibration loadPlateCalibration(const std::string& path) {
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
    if (key != "plate" && key != "source") throw ConfigError(path + ": unknown key '" + key + "'");
  }
  const YAML::Node plate = root["plate"];
  if (!plate || !plate.IsMap() || !plate["alpha_deg"]) {
    throw ConfigError(path + ": missing key 'plate.alpha_deg'");
  }
  for (const auto& kv : plate) {
    if (kv.first.as<std::string>() != "alpha_deg") {
      throw ConfigError(path + ": unknown key 'plate." + kv.first.as<std::string>() + "'");
    }
  }
  PlateCalibration c;
  try {
    c.alpha_deg = plate["alpha_deg"].as<double>();
  } catch (const YAML::Exception&) {
    throw ConfigError(path + ": key 'plate.alpha_deg' is not a number");
  }
  if (!std::isfinite(c.alpha_deg)) throw ConfigError(path + ": key 'plate.alpha_deg' not finite");
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

void writePlateCalibration(const std::string& path, const PlateCalibration& c) {
  YAML::Emitter em;
  em << YAML::BeginMap;
  em << YAML::Key << "plate" << YAML::Value << YAML::BeginMap;
  std::ostringstream alpha;
  alpha << std::setprecision(12) << c.alpha_deg;
  em << YAML::Key << "alpha_deg" << YAML::Value << alpha.str();
  em << YAML::EndMap;
  em << YAML::Key << "source" << YAML::Value << YAML::BeginMap;
  for (const auto& [k, v] : c.source) em << YAML::Key << k << YAML::Value << v;
  em << YAML::Key << "logs" << YAML::Value << YAML::BeginSeq;
  for (const auto& l : c.logs) em << l;
  em << YAML::EndSeq << YAML::EndMap << YAML::EndMap;

  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::trunc);
    f << "# Plate-angle calibration (Yuan 2021 Algorithm A1); read via plate.calibration_file\n"
      << em.c_str() << "\n";
    f.flush();
    if (!f) throw std::runtime_error(tmp + ": write failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot replace (rename failed)");
  }
}

}  // namespace sweepmap
