// `sweepmap launch`: a deployment's processes in the foreground, for a bench or a laptop —
// what systemd does on a host (`sweepmap systemd`), without installing anything.
//
// Starts the processes of one host (or of every host) in file order, each with its output in
// LOG_DIR/<name>.txt (appended across restarts) and in a process group of its own (a
// terminal's Ctrl-C reaches launch alone, which stops them in order; when a process ends,
// what it left running in its group is killed, as systemd kills a unit's cgroup). A process that
// dies is restarted after restart.delay_s, doubling per failure in a row up to restart.max_delay_s;
// one that ran restart.stable_s starts again at delay_s. A process that exits 0 has finished and is
// not restarted, unless its `restart` is `always`. Launch provides the children's $NOTIFY_SOCKET
// (an abstract socket) and WATCHDOG_USEC: a process that speaks sd_notify and sends no
// WATCHDOG=1 for restart.watchdog_s is hung — it is killed (SIGKILL) and restarted, as systemd
// does. SIGINT/SIGTERM stop the processes in reverse file order (upstream first when the file
// lists consumers first): SIGINT, then SIGKILL after the stop timeout. Every start, ready,
// exit (with its status), restart and watchdog kill is printed, and kept in LOG_DIR/launch.txt.
#pragma once

#include <string>

namespace sweepmap {

struct LaunchOptions {
  std::string deploy;  // deployment file
  std::string host;    // "" = every host's processes
  std::string log_dir = "launch-logs";
  std::string bin_dir;  // the sweepmap executables; "" = the folder of this executable
  bool watchdog = true;
  // --allow-senders (the hosts' addresses) and --key-file (the file's key_file) for every
  // process that takes them, as the systemd units have; off on a bench.
  bool secure = false;
};

// Returns 0 after a clean stop (a signal, or every process finished), 1 when a process had to
// be killed at stop, 2 for a bad deployment file or log folder.
int runLaunch(const LaunchOptions& options);

}  // namespace sweepmap
