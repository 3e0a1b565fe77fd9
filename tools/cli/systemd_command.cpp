// `sweepmap systemd DEPLOY --host H --out DIR`: the host's systemd units
// (tools/ops/systemd_units.hpp).
#include <iostream>

#include "core/config.hpp"
#include "core/exit_codes.hpp"
#include "tools/cli/commands.hpp"
#include "tools/ops/systemd_units.hpp"

namespace sweepmap {

Runner addSystemdCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "systemd",
      "Write one host's part of a deployment file (config/deploy_*.yaml) as systemd units into "
      "--out DIR: sweepmap-<process>.service for each of its processes (Type=notify with "
      "WatchdogSec: the processes ping from their worker loops, so a hung one is restarted; "
      "Restart=on-failure after RestartSec; SIGINT to stop, SIGKILL after TimeoutStopSec; the "
      "LCM URL; started after network-online.target and time-sync.target) and "
      "sweepmap-<host>.target that starts and stops them together. Install: copy them to "
      "/etc/systemd/system, `systemctl daemon-reload`, `systemctl enable --now "
      "sweepmap-<host>.target`. Secure by default: every sweepmap process and `sweepmap record` "
      "get "
      "--allow-senders (the file's host addresses) and --key-file (its key_file, default "
      "/etc/sweepmap/lcm.key: install it on every host with mode 0400 before starting)");
  struct Options {
    std::string deploy, host, out, bin_dir = "/usr/bin";
    bool insecure = false;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("DEPLOY", o->deploy, "deployment file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--host", o->host, "the host whose processes the units run")->required();
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->add_option("--bin-dir", o->bin_dir,
                  "where the sweepmap executables are installed on that host")
      ->capture_default_str();
  cmd->add_flag("--insecure", o->insecure,
                "no --allow-senders nor --key-file in the units: any host on the network is "
                "heard, nothing is signed (a bench network only)");
  return [o]() -> int {
    try {
      const Deployment d = loadDeployment(o->deploy);
      for (const auto& path : writeSystemdUnits(d, o->host, o->bin_dir, o->out, !o->insecure)) {
        std::cout << path << "\n";
      }
    } catch (const ConfigError& e) {
      std::cerr << "sweepmap systemd: " << e.what() << "\n";
      return kExitUsage;
    }
    return kExitOk;
  };
}

}  // namespace sweepmap
