// Command-line options every process shares.
#pragma once

#include <CLI/CLI.hpp>

#include <iostream>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/rig_config.hpp"
#include "processes/channels.hpp"
#include "processes/rig_b.hpp"

namespace sweepmap {

struct CommonOptions {
  std::string rig_path;
  std::string rig_b_path;  // processes that also serve rig B (assembler, mapper): --rig-b
  std::vector<std::string> overrides;
  std::string lcm_url = kDefaultLcmUrl;
};

inline void addCommonOptions(CLI::App& app, CommonOptions& o) {
  app.add_option("--rig", o.rig_path, "rig config file (YAML)")->required()->check(CLI::ExistingFile);
  app.add_option("--set", o.overrides, "override a rig config key: key=value (repeatable)");
  app.add_option("--lcm-url", o.lcm_url, "LCM provider URL")->capture_default_str();
}

// For processes that serve both rigs: exactly one of --rig (rig A) and --rig-b (rig B).
inline void addRigAOrBOptions(CLI::App& app, CommonOptions& o) {
  auto* a = app.add_option("--rig", o.rig_path, "rig A config file (YAML): rotating rig mode")
                ->check(CLI::ExistingFile);
  auto* b = app.add_option("--rig-b", o.rig_b_path,
                           "rig B config file (YAML): lidar on a moving base (world frame)")
                ->check(CLI::ExistingFile);
  a->excludes(b);
  app.add_option("--set", o.overrides, "override a rig config key: key=value (repeatable)");
  app.add_option("--lcm-url", o.lcm_url, "LCM provider URL")->capture_default_str();
  app.final_callback([&app, &o] {
    if (o.rig_path.empty() && o.rig_b_path.empty()) {
      throw CLI::RequiredError("one of --rig and --rig-b");
    }
  });
}

// Loads the rig or prints the error (naming file and key) and exits with status 2.
inline RigConfig loadRigOrExit(const CommonOptions& o) {
  try {
    return loadRig(o.rig_path, o.overrides);
  } catch (const std::exception& e) {
    std::cerr << "config error: " << e.what() << "\n";
    std::exit(2);
  }
}

inline RigBConfig loadRigBOrExit(const CommonOptions& o) {
  try {
    return loadRigB(o.rig_b_path, o.overrides);
  } catch (const std::exception& e) {
    std::cerr << "config error: " << e.what() << "\n";
    std::exit(2);
  }
}

}  // namespace sweepmap
