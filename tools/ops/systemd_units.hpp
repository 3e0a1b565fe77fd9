// `sweepmap systemd`: one host's part of a deployment as systemd units — one
// sweepmap-<process>.service per process and a sweepmap-<host>.target that groups them.
//
// Each service: Type=notify with WatchdogSec (the sweepmap processes send READY=1 and
// WATCHDOG=1 from their worker loops, so a hung process is restarted, not only a dead one;
// Type=simple for a command that does not, e.g. lcm-logger), Restart=on-failure (or always)
// after RestartSec, SIGINT to stop and SIGKILL after TimeoutStopSec, the LCM URL on its command
// line and in LCM_DEFAULT_URL, started after network-online.target and time-sync.target (a Pi
// has no RTC: its clock must be set first), in /var/lib/sweepmap (StateDirectory: relative
// paths of the arguments land there), PartOf= and WantedBy= the target. Secure by default:
// every sweepmap process and `sweepmap record` hear only the deployment's hosts
// (--allow-senders) and sign and check every message with its shared key (--key-file); a
// process refuses a key file that its group or others may read (exit 2), and exit 2 (a usage
// or config error) is not restarted (RestartPreventExitStatus=2).
#pragma once

#include <string>
#include <vector>

#include "tools/ops/deploy.hpp"

namespace sweepmap {

struct UnitFile {
  std::string name;  // e.g. sweepmap-motor.service
  std::string text;
};

// The units of `host` (throws ConfigError for an unknown host); the sweepmap executables are
// taken from `bin_dir`. `secure` = false: no --allow-senders nor --key-file (a bench).
std::vector<UnitFile> systemdUnits(const Deployment& d, const std::string& host,
                                   const std::string& bin_dir, bool secure = true);

// Writes them into `out_dir` (created if needed), each atomically; returns their paths.
std::vector<std::string> writeSystemdUnits(const Deployment& d, const std::string& host,
                                           const std::string& bin_dir, const std::string& out_dir,
                                           bool secure = true);

// One argument as systemd's command-line syntax reads it back unchanged (quotes where
// needed, '%' and '$' doubled, '\' and '"' escaped).
std::string systemdQuote(const std::string& arg);

}  // namespace sweepmap
