// Command-line options every process shares: --rig (a rig file of any kind, or a rig's
// name such as rig_a), --set, --lcm-url, --queue-capacity, --allow-senders and --key-file.
#pragma once

#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "core/command_line.hpp"
#include "net/message_auth.hpp"
#include "net/udpm_receiver.hpp"
#include "processes/channels.hpp"
#include "processes/live_runner.hpp"
#include "rigs/rig_file.hpp"

namespace sweepmap {

struct CommonOptions {
  std::string rig_path;
  std::vector<std::string> overrides;
  std::string lcm_url = kDefaultLcmUrl;
  size_t queue_capacity = 0;               // --queue-capacity; 0: the rig's network.queue_messages
  std::vector<std::string> allow_senders;  // --allow-senders
  std::string key_file;                    // --key-file
  // Parsed from the two above by loadRigOrReport.
  std::set<uint32_t> allowed_senders;
  std::shared_ptr<const net::MessageAuth> auth;
  // The rig's receive-path bounds (network.*), copied by loadRigOrReport.
  NetworkConfig network;
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
                 "counted (`dropped` in the status); default: the rig's network.queue_messages")
      ->check(atLeast(1));
  app.add_option("--allow-senders", o.allow_senders,
                 "receive only from these IPv4 addresses (comma-separated; counted as "
                 "`net_not_allowed` in the status); default: any sender")
      ->delimiter(',');
  app.add_option("--key-file", o.key_file,
                 "shared key (32 bytes or 64 hex digits, chmod 600): sign every message "
                 "published and drop every message received unsigned or wrongly signed "
                 "(`net_not_signed`); default: no signing");
}

// --allow-senders and --key-file into `o`; throws std::invalid_argument naming the option.
inline void parseSecurityOptions(CommonOptions& o) {
  net::ReceiverOptions r = net::securityOptions(o.lcm_url, o.allow_senders, o.key_file);
  o.allowed_senders = std::move(r.allowed_senders);
  if (r.auth) o.auth = std::make_shared<net::MessageAuth>(*r.auth);
}

// A device driver's worker thread silent this long is stuck (its reads, connection attempts and
// start-up exchanges all time out sooner): the process withholds its watchdog ping.
constexpr int64_t kDeviceWorkerStallMs = 10000;

// The datagram reassembler's bounds from a rig's network.* keys.
inline net::ReassemblyLimits reassemblyLimits(const NetworkConfig& n) {
  constexpr double kMiB = 1 << 20;
  net::ReassemblyLimits l;
  l.max_message_bytes = static_cast<size_t>(n.max_message_mib * kMiB);
  l.max_pending_per_sender = static_cast<size_t>(n.pending_messages_per_sender);
  l.max_pending_bytes_per_sender = static_cast<size_t>(n.pending_mib_per_sender * kMiB);
  l.max_pending_bytes = static_cast<size_t>(n.pending_mib * kMiB);
  l.max_senders = static_cast<size_t>(n.max_senders);
  l.fragment_timeout_us = static_cast<int64_t>(n.fragment_timeout_s * 1e6);
  return l;
}

// The live runner's options: the URL, the security options and the rig's bounds (the
// command line's --queue-capacity over network.queue_messages).
inline LiveOptions liveOptions(const CommonOptions& o) {
  LiveOptions options(o.lcm_url);
  options.allowed_senders = o.allowed_senders;
  options.auth = o.auth;
  options.queue_capacity =
      o.queue_capacity > 0 ? o.queue_capacity : static_cast<size_t>(o.network.queue_messages);
  options.queue_capacity_bytes = static_cast<size_t>(o.network.queue_mib * (1 << 20));
  options.reassembly = reassemblyLimits(o.network);
  return options;
}

// Loads the rig and reads the security options; on error prints "config error: ..." (naming
// file and key, or the option) and returns nothing: the process's main() then exits with
// status 2 (kExitUsage).
inline std::optional<Rig> loadRigOrReport(CommonOptions& o) {
  try {
    parseSecurityOptions(o);
    Rig rig = loadRig(o.rig_path, o.overrides);
    o.network = std::visit([](const auto& c) { return c.network; }, rig.config);
    return rig;
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
