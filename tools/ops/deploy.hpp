// A deployment file (config/deploy_*.yaml): which processes run on which host, with which
// arguments, on which LCM URL, and how they are restarted. `sweepmap systemd` turns one
// host's part into systemd units, `sweepmap launch` runs it in the foreground.
//
//   lcm_url: udpm://239.255.76.67:7667?ttl=1&recv_buf_size=2097152
//   restart: {delay_s: 0.5, max_delay_s: 10, stable_s: 60, watchdog_s: 5, stop_timeout_s: 30}
//   hosts:
//     pi:
//       address: 192.168.1.20
//       processes:
//         - {name: motor, command: sweepmap-motor, args: [--rig, rig_a]}
//
// Every process gets `--lcm-url URL` appended to its arguments and LCM_DEFAULT_URL=URL in its
// environment. With security on (the generated systemd units; `sweepmap launch --secure`),
// every sweepmap process and `sweepmap record` also get `--allow-senders` (the hosts'
// addresses) and `--key-file` (the file's optional `key_file`, default
// /etc/sweepmap/lcm.key). Unknown keys, missing keys and bad values are errors naming the file, the
// line and column, and the key.
#pragma once

#include <string>
#include <vector>

namespace sweepmap {

struct RestartPolicy {
  double delay_s = 0.5;        // first restart delay; doubles per failure in a row (launch)
  double max_delay_s = 10.0;   // the doubling stops here
  double stable_s = 60.0;      // a process that ran this long starts again at delay_s
  double watchdog_s = 5.0;     // WatchdogSec: no WATCHDOG=1 for this long = hung
  double stop_timeout_s = 30;  // SIGINT, then SIGKILL after this long
};

struct DeployProcess {
  std::string name;     // unique in the file: unit sweepmap-<name>.service, log <name>.txt
  std::string command;  // sweepmap-* and sweepmap from the bin folder, others from PATH
  std::vector<std::string> args;
  bool restart_always = false;  // restart: always (else on-failure: an exit 0 ends it)
  bool notify = true;           // speaks sd_notify (READY, WATCHDOG): the sweepmap-* processes
  double stop_timeout_s = 0;    // per process; 0 = the policy's
};

struct DeployHost {
  std::string name;
  std::string address;
  std::vector<DeployProcess> processes;
};

// The shared key's default place on every host (mode 0400, owned by the service user).
inline const char* const kDefaultDeployKeyFile = "/etc/sweepmap/lcm.key";

struct Deployment {
  std::string path;  // the file it was read from
  std::string lcm_url;
  std::string key_file = kDefaultDeployKeyFile;
  RestartPolicy restart;
  std::vector<DeployHost> hosts;

  // Throws ConfigError naming the file when there is no such host (and listing the hosts).
  const DeployHost& host(const std::string& name) const;
  // The processes of `host`, or of every host in file order when `host` is empty.
  std::vector<DeployProcess> processes(const std::string& host) const;
  double stopTimeout(const DeployProcess& p) const {
    return p.stop_timeout_s > 0 ? p.stop_timeout_s : restart.stop_timeout_s;
  }
  // Every host's address, comma-separated in file order: the senders a process may hear.
  std::string senderAddresses() const;
};

// Whether a process takes --allow-senders and --key-file: the sweepmap-* processes and
// `sweepmap record`.
bool takesSecurityOptions(const DeployProcess& p);

// Throws ConfigError ("FILE:LINE:COL: key 'hosts.pi.processes[1].args': ...").
Deployment loadDeployment(const std::string& path);
Deployment parseDeployment(const std::string& yaml_text, const std::string& source);

// argv of a process: the command (resolved in `bin_dir` for sweepmap and sweepmap-*, left
// for PATH otherwise), its args, then --lcm-url URL; with `secure`, then --allow-senders and
// --key-file for a process that takes them (takesSecurityOptions).
std::vector<std::string> processArgv(const Deployment& d, const DeployProcess& p,
                                     const std::string& bin_dir, bool secure = false);

}  // namespace sweepmap
