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
      "sweepmap-<host>.target`");
  struct Options {
    std::string deploy, host, out, bin_dir = "/usr/bin";
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("DEPLOY", o->deploy, "deployment file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--host", o->host, "the host whose processes the units run")->required();
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->add_option("--bin-dir", o->bin_dir,
                  "where the sweepmap executables are installed on that host")
      ->capture_default_str();
  return [o]() -> int {
    try {
      const Deployment d = loadDeployment(o->deploy);
      for (const auto& path : writeSystemdUnits(d, o->host, o->bin_dir, o->out)) {
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
