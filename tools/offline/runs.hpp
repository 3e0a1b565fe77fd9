// Simulation and replay of any rig kind: the one entry point `sweepmap sim`, `sweepmap
// replay` and the demo use. Each dispatches on the rig's kind to that kind's simulator
// (offline/simulation.hpp, offline/sim_mobile.hpp) or replay (offline/replay.hpp,
// offline/replay_mobile.hpp).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "processes/node.hpp"
#include "rigs/rig_file.hpp"
#include "sim/scene.hpp"

namespace sweepmap {

// A rig and the scene its simulator drives through.
struct SimSetup {
  Rig rig;
  SceneConfig scene;
  std::string scene_path;
};

// Loads the rig (path or name), and the scene (path or name; "" = the kind's default scene).
// `key=value` overrides starting with "scene." go to the scene, the others to the rig.
// Throws ConfigError naming file and key.
SimSetup loadSimSetup(const std::string& rig, const std::string& scene,
                      const std::vector<std::string>& overrides);

// `--print-config`: every rig and scene key with its value, unit, meaning and default.
void printSimConfig(std::ostream& out, const SimSetup& setup);

struct SimRunOptions {
  uint64_t seed = 1;
  int sweeps = 1;  // rotating_lidar: 3D sweeps to make (mobile_lidar: sim.duration_s decides)
  bool progress = false;  // progress on stderr when it is a terminal (core/progress.hpp)
};

struct SimRunResult {
  bool ok = false;      // every sweep made, no fault
  std::string summary;  // one line for the user
};

// Simulates the rig and sends every raw and ground-truth message to `sink` in time order.
// Throws ConfigError for a configuration the simulator cannot run.
SimRunResult simulateRig(const SimSetup& setup, const SimRunOptions& options,
                         const std::function<void(const Message&)>& sink);

struct ReplayRunOptions {
  std::string log_path;
  std::string out_dir;
  bool plots = true;
  bool progress = false;  // progress on stderr when it is a terminal (core/progress.hpp)
};

struct ReplayRunResult {
  std::string summary;  // one line for the user
  int64_t sweeps = 0;   // rotating_lidar: 3D sweeps assembled; rotating_profile: turntable sweeps
  int64_t scans = 0;    // mobile_lidar: scans in the world cloud
  int64_t points = 0;
  bool log_error = false;  // truncated or corrupt log: outputs up to it were kept
  std::string error;
  bool nothing = false;  // no sweep (scan, for mobile_lidar) made: `error` says why
};

// Replays a log through the rig kind's processes (offline, virtual clock) into out_dir. A
// replay that made nothing (an empty log, a log of another rig kind) sets `nothing` and says in
// `error` what the rig's kind needs and what the log holds (explainEmptyReplay).
ReplayRunResult replayRig(const Rig& rig, const ReplayRunOptions& options);

// The events of each channel of a log (a corrupt region skipped).
std::map<std::string, int64_t> logChannelCounts(const std::string& log_path);

// Why a replay with `rig` made nothing of the log: what the rig's kind needs (channels, and
// ranges per LIDAR_SCAN), what the log holds, and the rig kind its channels look like.
std::string explainEmptyReplay(const Rig& rig, const std::string& log_path);

}  // namespace sweepmap
