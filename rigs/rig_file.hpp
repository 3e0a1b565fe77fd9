// Loading any rig file: the kind from its `rig` key, then that kind's strict schema. Names
// as well as paths: `--rig rig_b` is the file config/rig_b.yaml of the install tree
// (build tree or installed prefix, found from the running executable), wherever the
// command runs from.
#pragma once

#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include "rigs/mobile_lidar.hpp"
#include "rigs/rig_kind.hpp"
#include "rigs/rotating_lidar.hpp"
#include "rigs/rotating_profile.hpp"

namespace sweepmap {

// A loaded rig: the file it came from and its kind's config. One alternative per RigKind,
// in the same order.
struct Rig {
  std::string path;
  std::variant<RotatingLidarConfig, MobileLidarConfig, RotatingProfileConfig> config;
  RigKind kind() const { return static_cast<RigKind>(config.index()); }
  std::string kindName() const { return rigKindName(kind()); }
  // The lidar section of the lidar kinds; throws ConfigError for a rig without a 2D lidar
  // (rotating_profile).
  const LidarConfig& lidar() const;
};

// The folder of the default rig and scene files: $SWEEPMAP_CONFIG_DIR if set, else
// <executable's folder>/../share/sweepmap/config (the build copies the source config/ folder
// there, again whenever a file changes; `make install` copies it there too).
std::filesystem::path configDir();

// A config file given by path or by name: an existing path is returned as is; otherwise
// `name` or `name.yaml` in configDir(). For rig files a kind's name stands for its
// reference rig (rotating_lidar -> rig_a). Throws ConfigError listing what was tried.
std::string resolveConfigFile(const std::string& path_or_name);
// The same, naming `what` ("rig", "scene") in its error, which lists the files of configDir()
// whose names start with `prefix` ("rig_", "scene_").
std::string resolveConfigFile(const std::string& path_or_name, const std::string& what,
                              const std::string& prefix);
// A rig: its error lists the rigs there are (and the kinds' names that stand for them).
std::string resolveRigFile(const std::string& path_or_name);
// A scene: its error lists the scenes there are.
std::string resolveSceneFile(const std::string& path_or_name);
// The names (file stems) of the .yaml files in configDir() starting with `prefix`, sorted.
std::vector<std::string> configNames(const std::string& prefix);

// The kind a rig file declares (its `rig` key alone). Throws ConfigError naming the file.
RigKind readRigKind(const std::string& path);

// Resolves, reads the kind, loads that kind's schema strictly and applies `key=value`
// overrides. Throws ConfigError naming the file and the key (or `--set key=value` when the
// value an override set fails the kind's checks).
Rig loadRig(const std::string& path_or_name, const std::vector<std::string>& overrides = {});

// Loads the rig file rig->path as `kind` into rig->config (loadRig's second half).
void loadRigOfKind(RigKind kind, Rig* rig, const std::vector<std::string>& overrides);

// The rig's config if it is of kind T; throws ConfigError "PATH is a KIND rig; WHAT needs a
// KIND2 rig" otherwise.
template <class T>
const T& requireKind(const Rig& rig, const std::string& what);

}  // namespace sweepmap
