// `sweepmap dump`: an LCM log's messages decoded (tools/offline/dump.hpp).
#include <iostream>

#include "tools/cli/commands.hpp"
#include "tools/offline/dump.hpp"

namespace sweepmap {

Runner addDumpCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "dump",
      "Print an LCM log's messages decoded, in log order: each with its log time, channel, type "
      "and every field by its name in the .lcm files this build was made from (long arrays "
      "shortened; --full prints them whole; a field that takes the type's constants shows the "
      "constant's name too: `state = 4 (SCANNING)`). --json: one JSON object per message per line "
      "with \"channel\", \"log_utime\", \"type\" and the fields (arrays whole; NaN and "
      "infinities as null). A message of no known type is shown with its size and first bytes. "
      "Corrupt or truncated bytes are skipped to the next good event header (as LCM's own "
      "reader does): every event outside them is printed, each skipped byte range is "
      "reported on stderr where it occurs, and the exit status is 1. A log without a message "
      "exits 1; a --channel the log does not have exits 2, listing the channels it has.");
  auto o = std::make_shared<DumpOptions>();
  cmd->add_option("log", o->log, "LCM log file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--channel", o->channel,
                  "only this channel (exact name; one the log does not have is an error)");
  cmd->add_flag("--json", o->json, "one JSON object per message per line");
  cmd->add_flag("--full", o->full, "print arrays whole");
  return [o]() { return runDump(*o, std::cout, std::cerr); };
}

}  // namespace sweepmap
