// `sweepmap export mcap`: LCM logs as one MCAP file (viz/mcap_writer.hpp) that Foxglove and
// Lichtblick open with the 3D panel working: every LCM channel raw (message encoding "lcm",
// schema the type's .lcm text), and the derived Foxglove topics of viz/foxglove_messages.hpp
// (JSON encoding, the @foxglove/schemas JSON schemas) with the rig's frames.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "rigs/rig_file.hpp"

namespace sweepmap {

struct ExportMcapOptions {
  std::vector<std::string> logs;  // merged in log-time order (e.g. raw.lcmlog + derived.lcmlog)
  std::string out;
  bool raw = true;   // the raw LCM channels as well
  bool zstd = true;  // chunk compression
};

struct ExportMcapResult {
  int64_t events = 0;                       // LCM events read
  std::map<std::string, int64_t> topics;    // messages written per MCAP topic
  std::map<std::string, int64_t> rejected;  // LCM messages that did not decode, per channel
  int64_t messages = 0;                     // every message written
  uint64_t bytes = 0;                       // size of the MCAP file
  bool log_error = false;                   // corrupt or truncated bytes were skipped
  std::string error;
};

// Throws LogError for a log that cannot be opened, std::runtime_error for an unwritable out.
ExportMcapResult exportMcap(const Rig& rig, const ExportMcapOptions& options);

}  // namespace sweepmap
