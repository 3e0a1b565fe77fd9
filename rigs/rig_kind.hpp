// The kinds of rig sweepmap serves. A rig file names its kind in its `rig` key; each kind
// has its own strict schema (rigs/rotating_lidar.hpp, rigs/mobile_lidar.hpp,
// rigs/rotating_profile.hpp), and every
// command and process reads the kind from the file. Adding a rig means adding a kind here,
// its config struct to rigs/rig_file.hpp's Rig, and its branch where a command dispatches
// (the compiler lists every such place: std::visit over Rig::config).
#pragma once

#include <string>
#include <vector>

#include "core/config.hpp"

namespace sweepmap {

enum class RigKind {
  kRotatingLidar,    // rig A: 2D lidar turned by a stepper, plate correction (Yuan 2021)
  kMobileLidar,      // rig B: 2D lidar on a differential-drive car, odometry + IMU (Miao 2022)
  kRotatingProfile,  // rig C: profile sensor on a turntable, axis offsets M, N (Zhao 2021)
};

// "rotating_lidar", "mobile_lidar", "rotating_profile": the value of a rig file's `rig` key.
std::string rigKindName(RigKind kind);
// Every kind's name, in declaration order.
std::vector<std::string> rigKindNames();
// The kind named `name`; throws ConfigError (naming `source`) for an unknown one.
RigKind rigKindFromName(const std::string& name, const std::string& source);
// The rig file of the kind's reference rig, by name ("rig_a", "rig_b", "rig_c").
std::string defaultRigName(RigKind kind);
// The scene its simulator uses by default, by name ("scene_conference_room", "scene_lab";
// rotating_profile: "plate", a scene named by its sim.scene key, not a file).
std::string defaultSceneName(RigKind kind);

// Throws ConfigError "PATH: key 'rig' is KIND_FOUND, expected EXPECTED" when a file of one
// kind is loaded as another.
void checkRigKind(const std::string& path, const std::string& found, const std::string& expected);

// The first steps of loading a rig file of one kind into `config` through `schema`: its keys
// declared, the file read, the `key=value` overrides applied, the kind checked (checkRigKind).
template <class Config>
void loadRigSchema(const std::string& path, const std::vector<std::string>& overrides,
                   const std::string& kind, Config* config, ConfigSchema* schema) {
  config->declare(*schema);
  schema->loadFile(path);
  for (const auto& o : overrides) schema->set(o);
  checkRigKind(path, config->rig, kind);
}

// A file a rig file names (a calibration file): a relative `file` is relative to the rig
// file's folder. Returns load(resolved path); a ConfigError it throws is rethrown naming the
// rig file, the key, and what the path was relative to.
template <class Load>
auto loadFileBesideRig(const std::string& rig_path, const std::string& key, const std::string& file,
                       Load&& load) -> decltype(load(file));
// The path `file` stands for in the rig file `rig_path` (relative to its folder).
std::string pathBesideRig(const std::string& rig_path, const std::string& file);
// Throws ConfigError "RIG: key 'KEY' names 'FILE' (relative to the rig file's folder DIR:
// RESOLVED): ERROR".
[[noreturn]] void throwBesideRigError(const std::string& rig_path, const std::string& key,
                                      const std::string& file, const std::string& error);

// The keys whose values a rig calibration file gave (those no `--set` replaced), and the file.
struct CalibratedKeys {
  std::string file;  // as resolved beside the rig file
  std::vector<std::string> keys;
};

// A rig calibration file (sweepmap calib rig; core/calibration_file.hpp) that the rig file
// names in its top-level `calibration_file` key, applied over the loaded `schema`: each of its
// keys replaces the rig file's value, then the command line's `key=value` overrides are
// applied again (they win). Returns the file and the keys whose values it gave. Throws
// ConfigError naming the file and the key for a key the schema does not have, or one that
// cannot be calibrated (the kind, a calibration file).
CalibratedKeys applyRigCalibration(const std::string& rig_path, const std::string& file,
                                   const std::vector<std::string>& overrides, ConfigSchema* schema);

// `message` (a range check's of the rig file `rig_path`, beginning with that path) naming the
// calibration file instead when it is about a key whose value that file gave: "CALIBRATION:
// key 'K' must be ... (its parameters.K, applied by the calibration_file of rig file RIG)";
// otherwise `message` unchanged.
std::string calibrationSourceOf(const std::string& rig_path, const std::string& message,
                                const CalibratedKeys& calibrated);

// Runs `check` (the rig file's range checks); a ConfigError it throws is rethrown through
// calibrationSourceOf.
template <class Check>
void checkCalibratedRig(const std::string& rig_path, const CalibratedKeys& calibrated,
                        Check&& check) {
  try {
    check();
  } catch (const ConfigError& e) {
    throw ConfigError(calibrationSourceOf(rig_path, e.what(), calibrated));
  }
}

template <class Load>
auto loadFileBesideRig(const std::string& rig_path, const std::string& key, const std::string& file,
                       Load&& load) -> decltype(load(file)) {
  try {
    return load(pathBesideRig(rig_path, file));
  } catch (const std::exception& e) {
    throwBesideRigError(rig_path, key, file, e.what());
  }
}

}  // namespace sweepmap
