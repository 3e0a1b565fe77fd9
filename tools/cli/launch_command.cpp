// `sweepmap launch DEPLOY [--host H] [--log-dir DIR]`: the foreground supervisor
// (tools/ops/launch.hpp).
#include "tools/cli/commands.hpp"
#include "tools/ops/launch.hpp"

namespace sweepmap {

Runner addLaunchCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "launch",
      "Run a deployment's processes in the foreground (a bench, a laptop): those of --host, or "
      "of every host. One log file per process in --log-dir (appended across restarts) and "
      "every start, exit (with its status) and restart printed. A process that fails is "
      "restarted after restart.delay_s, doubling up to restart.max_delay_s (reset after "
      "restart.stable_s of running); one that exits 0 has finished (unless restart: always); "
      "one that sends no sd_notify WATCHDOG=1 for restart.watchdog_s is killed and restarted. "
      "SIGINT/SIGTERM stop them in reverse file order: SIGINT, then SIGKILL after the stop "
      "timeout");
  auto o = std::make_shared<LaunchOptions>();
  cmd->add_option("DEPLOY", o->deploy, "deployment file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--host", o->host, "run this host's processes (default: every host's)");
  cmd->add_option("--log-dir", o->log_dir, "one log file per process, and launch.txt")
      ->capture_default_str();
  cmd->add_option("--bin-dir", o->bin_dir,
                  "where the sweepmap executables are (default: beside this one)");
  auto no_watchdog = std::make_shared<bool>(false);
  cmd->add_flag("--no-watchdog", *no_watchdog,
                "do not watch the processes' WATCHDOG=1 (a debugger's breakpoint is no hang)");
  cmd->add_flag("--secure", o->secure,
                "as the systemd units do: every sweepmap process and `sweepmap record` hear only "
                "the file's host addresses (--allow-senders) and sign with its key_file "
                "(--key-file); default off (a bench)");
  return [o, no_watchdog]() -> int {
    o->watchdog = !*no_watchdog;
    return runLaunch(*o);
  };
}

}  // namespace sweepmap
