// Subcommands of the `sweepmap` tool. Each registers itself on the CLI11 app and returns
// the function that runs it.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <ostream>
#include <string>

#include "core/config.hpp"

namespace sweepmap {

// `--print-config` of the simulators: every rig and scene key with its value, unit, meaning
// and the default in code. Rig is RigConfig or RigBConfig; Scene is SceneConfig.
template <class Rig, class Scene>
void printSimConfig(std::ostream& out, Rig rig, const std::string& rig_path, Scene scene,
                    const std::string& scene_path) {
  Rig rig_defaults{};
  Scene scene_defaults{};
  ConfigSchema rs, ss, rds, sds;
  rig.declare(rs);
  scene.declare(ss, "scene.");
  rig_defaults.declare(rds);
  scene_defaults.declare(sds, "scene.");
  out << "# rig (" << rig_path << ")\n";
  rs.print(out, &rds);
  out << "# scene (" << scene_path << "), keys prefixed scene. for --set\n";
  ss.print(out, &sds);
}

using Runner = std::function<int()>;

Runner addSimCommand(CLI::App& app);
Runner addReplayCommand(CLI::App& app);
Runner addDemoCommand(CLI::App& app, const std::string& argv0);
Runner addSpyCommand(CLI::App& app, const std::string& argv0);
Runner addBenchCommand(CLI::App& app);
Runner addCalibCommand(CLI::App& app);  // group: calib plate-angle, calib mounting
Runner addEvalCommand(CLI::App& app);   // group: eval rotating
Runner addImportCommand(CLI::App& app);  // group: import breezyslam
Runner addReplayMobileCommand(CLI::App& app);
Runner addSimMobileCommand(CLI::App& app);

}  // namespace sweepmap
