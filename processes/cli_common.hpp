// Command-line options every process shares: --rig (a rig file of any kind, or a rig's
// name such as rig_a), --set, --lcm-url and --queue-capacity.
#pragma once

#include <CLI/CLI.hpp>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "core/command_line.hpp"
#include "processes/channels.hpp"
#include "processes/live_runner.hpp"
#include "rigs/rig_file.hpp"

namespace sweepmap {

struct CommonOptions {
  std::string rig_path;
  std::vector<std::string> overrides;
  std::string lcm_url = kDefaultLcmUrl;
  size_t queue_capacity = LiveOptions{}.queue_capacity;
};

// --rig's help names the kinds this process takes, with their reference rigs' names.
inline std::string rigOptionHelp(std::initializer_list<RigKind> kinds) {
  std::string list, names;
  for (RigKind k : kinds) {
    list += (list.empty() ? "" : ", ") + rigKindName(k);
    names += (names.empty() ? "" : ", ") + defaultRigName(k);
  }
  return "rig file (YAML; its `rig` key says the kind) or a rig's name in the installed config "
         "folder; this process takes " +
         list + " rigs (" + names + ")";
}

inline void addCommonOptions(CLI::App& app, CommonOptions& o,
                             std::initializer_list<RigKind> kinds) {
  app.add_option("--rig", o.rig_path, rigOptionHelp(kinds))->required();
  app.add_option("--set", o.overrides, "override a rig config key: key=value (repeatable)");
  app.add_option("--lcm-url", o.lcm_url, "LCM provider URL")->capture_default_str();
  app.add_option("--queue-capacity", o.queue_capacity,
                 "receive queue bound [messages]; a message that finds it full is dropped and "
                 "counted (`dropped` in the status)")
      ->capture_default_str()
      ->check(atLeast(1));
}

// A device driver's worker thread silent this long is stuck (its reads, connection attempts and
// start-up exchanges all time out sooner): the process withholds its watchdog ping.
constexpr int64_t kDeviceWorkerStallMs = 10000;

// The live runner's options with the command line's queue bound.
inline LiveOptions liveOptions(const CommonOptions& o) {
  LiveOptions options;
  options.queue_capacity = o.queue_capacity;
  return options;
}

// Loads the rig; on error prints "config error: ..." (naming file and key) and returns
// nothing: the process's main() then exits with status 2 (kExitUsage).
inline std::optional<Rig> loadRigOrReport(const CommonOptions& o) {
  try {
    return loadRig(o.rig_path, o.overrides);
  } catch (const std::exception& e) {
    std::cerr << "config error: " << e.what() << "\n";
    return std::nullopt;
  }
}

// The rig's config if it is of kind T (e.g. sweepmap-motor needs a rotating_lidar rig);
// otherwise prints the mismatch and returns nullptr.
template <class T>
const T* rigOfKindOrReport(const Rig& rig, const std::string& process) {
  try {
    return &requireKind<T>(rig, process);
  } catch (const std::exception& e) {
    std::cerr << "config error: " << e.what() << "\n";
    return nullptr;
  }
}

}  // namespace sweepmap
