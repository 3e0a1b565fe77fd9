// `sweepmap dump`: a log's messages decoded by the .lcm definitions (tools/offline/
// lcm_schema.hpp), in log order.
#pragma once

#include <ostream>
#include <string>

namespace sweepmap {

struct DumpOptions {
  std::string log;
  std::string channel;  // exact name; "" = all
  bool json = false;    // one JSON object per message per line
  bool full = false;    // human form: every array element, not the first few
};

// Writes to `out`; returns 0, or 1 when the log ends in a truncated or corrupt event (after
// printing every message before it; the error, with the byte offset, goes to `err`).
int runDump(const DumpOptions& options, std::ostream& out, std::ostream& err);

}  // namespace sweepmap
