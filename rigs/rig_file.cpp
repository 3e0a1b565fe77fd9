#include "rigs/rig_file.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdlib>
#include <iomanip>
#include <sstream>

#include "core/calibration_file.hpp"
#include "core/config.hpp"

namespace sweepmap {

namespace fs = std::filesystem;

namespace {

struct KindInfo {
  RigKind kind;
  const char* name;
  const char* default_rig;
  const char* default_scene;
};
constexpr KindInfo kKinds[] = {
    {RigKind::kRotatingLidar, "rotating_lidar", "rig_a", "scene_conference_room"},
    {RigKind::kMobileLidar, "mobile_lidar", "rig_b", "scene_lab"},
    {RigKind::kRotatingProfile, "rotating_profile", "rig_c", "plate"},
};

const KindInfo& info(RigKind kind) { return kKinds[static_cast<int>(kind)]; }

fs::path executableDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

}  // namespace

std::string rigKindName(RigKind kind) { return info(kind).name; }

std::vector<std::string> rigKindNames() {
  std::vector<std::string> names;
  for (const auto& k : kKinds) names.emplace_back(k.name);
  return names;
}

RigKind rigKindFromName(const std::string& name, const std::string& source) {
  for (const auto& k : kKinds) {
    if (name == k.name) return k.kind;
  }
  std::string known;
  for (const auto& k : kKinds) known += std::string(known.empty() ? "" : ", ") + k.name;
  throw ConfigError(source + ": key 'rig' is '" + name + "', not a rig kind (" + known + ")");
}

std::string defaultRigName(RigKind kind) { return info(kind).default_rig; }
std::string defaultSceneName(RigKind kind) { return info(kind).default_scene; }

void checkRigKind(const std::string& path, const std::string& found, const std::string& expected) {
  if (found != expected) {
    throw ConfigError(path + ": key 'rig' is '" + found + "', expected '" + expected + "'");
  }
}

std::string pathBesideRig(const std::string& rig_path, const std::string& file) {
  const fs::path p(file);
  return p.is_relative() ? (fs::path(rig_path).parent_path() / p).string() : file;
}

void throwBesideRigError(const std::string& rig_path, const std::string& key,
                         const std::string& file, const std::string& error) {
  std::string where = "an absolute path";
  if (fs::path(file).is_relative()) {
    const fs::path dir = fs::absolute(fs::path(rig_path)).parent_path();
    where = "relative to the rig file's folder " + dir.string() + ": " +
            (dir / file).lexically_normal().string();
  }
  throw ConfigError(rig_path + ": key '" + key + "' names '" + file + "' (" + where +
                    "): " + error);
}

namespace {

// The key an override `key=value` sets.
std::string overrideKey(const std::string& assignment) {
  return assignment.substr(0, assignment.find('='));
}

}  // namespace

CalibratedKeys applyRigCalibration(const std::string& rig_path, const std::string& file,
                                   const std::vector<std::string>& overrides,
                                   ConfigSchema* schema) {
  const RigCalibrationFile c =
      loadFileBesideRig(rig_path, "calibration_file", file, loadRigCalibration);
  const std::string where = pathBesideRig(rig_path, file);
  CalibratedKeys applied{where, {}};
  for (const auto& [key, value] : c.parameters) {
    if (key == "rig" || key.find("calibration_file") != std::string::npos) {
      throw ConfigError(where + ": key 'parameters." + key + "' cannot be calibrated");
    }
    if (!schema->has(key)) {
      throw ConfigError(where + ": key 'parameters." + key + "' is not a key of the rig file " +
                        rig_path + " (a calibration of another kind of rig?)");
    }
    std::ostringstream v;
    v << std::setprecision(17) << value;
    try {
      schema->set(key + "=" + v.str());
    } catch (const ConfigError& e) {
      throw ConfigError(where + ": key 'parameters." + key + "': " + e.what());
    }
    const bool overridden = std::any_of(overrides.begin(), overrides.end(),
                                        [&](const auto& o) { return overrideKey(o) == key; });
    if (!overridden) applied.keys.push_back(key);
  }
  for (const auto& o : overrides) schema->set(o);
  return applied;
}

namespace {

// A rig file's check's message without its leading "PATH: ".
std::string withoutSource(std::string what, const std::string& path) {
  if (what.rfind(path, 0) == 0) what = what.substr(path.size());
  if (what.rfind(": ", 0) == 0) what = what.substr(2);
  return what;
}

}  // namespace

std::string calibrationSourceOf(const std::string& rig_path, const std::string& message,
                                const CalibratedKeys& calibrated) {
  for (const auto& key : calibrated.keys) {
    if (message.find("'" + key + "'") == std::string::npos) continue;
    return calibrated.file + ": " + withoutSource(message, rig_path) + " (its parameters." + key +
           ", applied by the calibration_file of rig file " + rig_path + ")";
  }
  return message;
}

fs::path configDir() {
  if (const char* env = std::getenv("SWEEPMAP_CONFIG_DIR"); env && *env) return fs::path(env);
  return executableDir() / ".." / "share" / "sweepmap" / "config";
}

std::vector<std::string> configNames(const std::string& prefix) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(configDir(), ec)) {
    const fs::path p = entry.path();
    const std::string stem = p.stem().string();
    if (p.extension() == ".yaml" && stem.rfind(prefix, 0) == 0) names.push_back(stem);
  }
  std::sort(names.begin(), names.end());
  return names;
}

namespace {

// ": the rigs there are: rig_a, rig_b (in DIR)", or "" when none is found.
std::string thereAre(const std::string& what, const std::string& prefix) {
  const std::vector<std::string> names = configNames(prefix);
  if (names.empty()) return "";
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  return "; the " + what + " there are: " + list + " (in " +
         configDir().lexically_normal().string() + ")";
}

}  // namespace

std::string resolveConfigFile(const std::string& path_or_name) {
  return resolveConfigFile(path_or_name, "config file", "");
}

std::string resolveConfigFile(const std::string& path_or_name, const std::string& what,
                              const std::string& prefix) {
  if (path_or_name.empty()) throw ConfigError("no " + what + " given");
  if (fs::is_regular_file(path_or_name)) return path_or_name;
  std::vector<fs::path> tried = {fs::path(path_or_name)};
  // A bare name (no folder part) is looked up among the installed config files.
  if (fs::path(path_or_name).parent_path().empty()) {
    const fs::path dir = configDir();
    for (const fs::path& c : {dir / path_or_name, dir / (path_or_name + ".yaml")}) {
      if (fs::is_regular_file(c)) return fs::weakly_canonical(c).string();
      tried.push_back(c.lexically_normal());
    }
  }
  std::string list;
  for (const auto& t : tried) list += (list.empty() ? "" : ", ") + t.string();
  throw ConfigError(path_or_name + ": no such " + what + " (tried " + list + ")" +
                    (prefix.empty() ? "" : thereAre(what + "s", prefix)));
}

std::string resolveSceneFile(const std::string& path_or_name) {
  return resolveConfigFile(path_or_name, "scene", "scene_");
}

std::string resolveRigFile(const std::string& path_or_name) {
  for (const auto& k : kKinds) {
    if (path_or_name == k.name && !fs::exists(path_or_name)) {
      return resolveConfigFile(k.default_rig);
    }
  }
  try {
    return resolveConfigFile(path_or_name, "rig", "rig_");
  } catch (const ConfigError& e) {
    std::string kinds;
    for (const auto& k : kKinds) kinds += std::string(kinds.empty() ? "" : ", ") + k.name;
    throw ConfigError(std::string(e.what()) +
                      " (a kind's name stands for its reference rig: " + kinds + ")");
  }
}

RigKind readRigKind(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot open");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": " + e.what());
  }
  if (!root.IsMap() || !root["rig"]) {
    std::string known;
    for (const auto& k : kKinds) known += std::string(known.empty() ? "" : " | ") + k.name;
    throw ConfigError(path + ": missing key 'rig' (the rig's kind: " + known + ")");
  }
  if (!root["rig"].IsScalar()) throw ConfigError(path + ": key 'rig' must be a kind name");
  return rigKindFromName(root["rig"].as<std::string>(), path);
}

namespace {

// A rig file's check that failed on a key an override set: the error names --set, not the file.
[[noreturn]] void blameOverride(const std::string& path, const ConfigError& e,
                                const std::vector<std::string>& overrides) {
  std::string what = e.what();
  if (what.rfind("--set", 0) == 0) throw e;  // the override's own parse error names it already
  for (const std::string& o : overrides) {
    const std::string key = overrideKey(o);
    if (key.empty() || what.find("'" + key + "'") == std::string::npos) continue;
    throw ConfigError("--set " + o + ": " + withoutSource(what, path) + " (rig file " + path + ")");
  }
  throw e;
}

}  // namespace

Rig loadRig(const std::string& path_or_name, const std::vector<std::string>& overrides) {
  Rig rig;
  rig.path = resolveRigFile(path_or_name);
  const RigKind kind = readRigKind(rig.path);
  try {
    loadRigOfKind(kind, &rig, overrides);
  } catch (const ConfigError& e) {
    blameOverride(rig.path, e, overrides);
  }
  return rig;
}

void loadRigOfKind(RigKind kind, Rig* rig_out, const std::vector<std::string>& overrides) {
  Rig& rig = *rig_out;
  switch (kind) {
    case RigKind::kRotatingLidar:
      rig.config = loadRotatingLidarConfig(rig.path, overrides);
      break;
    case RigKind::kMobileLidar:
      rig.config = loadMobileLidarConfig(rig.path, overrides);
      break;
    case RigKind::kRotatingProfile:
      rig.config = loadRotatingProfileConfig(rig.path, overrides);
      break;
  }
}

const LidarConfig& Rig::lidar() const {
  if (const auto* a = std::get_if<RotatingLidarConfig>(&config)) return a->lidar;
  if (const auto* b = std::get_if<MobileLidarConfig>(&config)) return b->lidar;
  throw ConfigError(path + " is a " + kindName() + " rig: it has no 2D lidar");
}

namespace {

// The index of T among the variant's alternatives: the kind whose config type is T.
template <class T, class... Ts>
constexpr std::size_t alternativeIndex(const std::variant<Ts...>*) {
  constexpr bool same[] = {std::is_same_v<T, Ts>...};
  for (std::size_t i = 0; i < sizeof...(Ts); ++i) {
    if (same[i]) return i;
  }
  return sizeof...(Ts);
}

}  // namespace

template <class T>
const T& requireKind(const Rig& rig, const std::string& what) {
  if (const T* c = std::get_if<T>(&rig.config)) return *c;
  const auto wanted = static_cast<RigKind>(alternativeIndex<T>(&rig.config));
  throw ConfigError(rig.path + " is a " + rig.kindName() + " rig; " + what + " needs a " +
                    rigKindName(wanted) + " rig");
}
template const RotatingLidarConfig& requireKind(const Rig&, const std::string&);
template const MobileLidarConfig& requireKind(const Rig&, const std::string&);
template const RotatingProfileConfig& requireKind(const Rig&, const std::string&);

}  // namespace sweepmap
