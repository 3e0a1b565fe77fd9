// Command-line options every process shares.
#pragma once

#include <CLI/CLI.hpp>

#include <iostream>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/rig_config.hpp"
#include "processes/channels.hpp"

namespace sweepmap {

struct CommonOptions {
  std::string rig_path;
  std::vector<std::string> overrides;
  std::string lcm_url = kDefaultLcmUrl;
};

inline void addCommonOptions(CLI::App& app, CommonOptions& o) {
  app.add_option("--rig", o.rig_path, "rig config file (YAML)")->required()->check(CLI::ExistingFile);
  app.add_option("--set", o.overrides, "override a rig config key: key=value (repeatable)");
  app.add_option("--lcm-url", o.lcm_url, "LCM provider URL")->capture_default_str();
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

}  // namespace sweepmap
