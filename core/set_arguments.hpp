// How one sweepmap command passes rig-file overrides on to another it starts: each
// `key=value` after its own `--set` (the flag every command takes, core/config.hpp's
// ConfigSchema::set). Header-only: the benches, the demo and the tests share it.
#pragma once

#include <string>
#include <vector>

namespace sweepmap {

// Appends `--set key=value` to argv for each of `assignments`, in their order.
inline void appendSetArguments(std::vector<std::string>* argv,
                               const std::vector<std::string>& assignments) {
  for (const auto& kv : assignments) {
    argv->emplace_back("--set");
    argv->emplace_back(kv);
  }
}

// The `--set key=value` arguments for `assignments`.
inline std::vector<std::string> setArguments(const std::vector<std::string>& assignments) {
  std::vector<std::string> argv;
  appendSetArguments(&argv, assignments);
  return argv;
}

}  // namespace sweepmap
