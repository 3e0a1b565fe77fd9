// `sweepmap status`: every process's health at a glance (tools/ops/status.hpp).
#include "processes/channels.hpp"
#include "tools/cli/commands.hpp"
#include "tools/ops/status.hpp"

namespace sweepmap {

Runner addStatusCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "status",
      "A live dashboard of every sweepmap process on the LCM URL, from their STATUS_* messages: "
      "health (OK, DEGRADED, FAILED, or STALE when a process's status stops for --stale-s), "
      "counters, last detail; the message rate of every channel; the mapper's progress "
      "(MAP_STATS) and the assembler's last sweep (SWEEP_STATUS). Refreshes every second until "
      "Ctrl-C. --once listens for --window seconds and prints one snapshot (--json: one JSON "
      "object), its exit status the number of stale or failed processes");
  auto o = std::make_shared<StatusOptions>();
  o->lcm_url = kDefaultLcmUrl;
  cmd->add_option("--lcm-url", o->lcm_url, "LCM URL the processes publish on")
      ->capture_default_str();
  cmd->add_flag("--once", o->once, "print one snapshot after --window seconds and exit");
  cmd->add_flag("--json", o->json, "with --once: JSON instead of the table");
  cmd->add_option("--window", o->window_s, "with --once: seconds to listen")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--stale-s", o->board.stale_s,
                  "a process whose status has not come for this long is STALE")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  return [o]() { return runStatus(*o); };
}

}  // namespace sweepmap
