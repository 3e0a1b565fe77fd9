// `sweepmap status`: every process's health at a glance (tools/ops/status.hpp).
#include "processes/channels.hpp"
#include "tools/cli/commands.hpp"
#include "tools/ops/status.hpp"

namespace sweepmap {

Runner addStatusCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "status",
      "A live dashboard of every sweepmap process on the LCM URL, from the STATUS_* messages of "
      "the nodes they run: one row per process with its STATUS (OK, DEGRADED, FAILED: the worst "
      "of its nodes; STALE when its status stops for --stale-s), the AGE of its last status and "
      "its detail, each node's state and counters beneath; the message rate of every channel; "
      "the mapper's progress (MAP_STATS) and the assembler's last sweep (SWEEP_STATUS). "
      "Refreshes every second until Ctrl-C. --once listens for --window seconds and prints one "
      "snapshot (--json: one JSON object with the same fields); its exit status is 1 when no "
      "process was seen or one is STALE or FAILED, else 0");
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
  cmd->add_option("--allow-senders", o->allow_senders,
                  "hear only these IPv4 addresses (comma-separated), as the processes do")
      ->delimiter(',');
  cmd->add_option("--key-file", o->key_file,
                  "the deployment's shared key: read only statuses signed with it (where the "
                  "processes sign, unsigned bytes do not decode)");
  return [o]() { return runStatus(*o); };
}

}  // namespace sweepmap
