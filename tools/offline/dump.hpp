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

// Writes to `out`, errors to `err`. Returns 0 (kExitOk); 1 (kExitBadInput) when the log holds
// corrupt or truncated bytes (every message outside them is printed; each skipped range, with
// its byte offsets, goes to `err`) or no message at all; 2 (kExitUsage) when `channel` is not
// in the log (`err` lists the channels it has).
int runDump(const DumpOptions& options, std::ostream& out, std::ostream& err);

}  // namespace sweepmap
