// Starting, stopping and waiting for child processes (used by `sweepmap demo`, `sweepmap
// launch` and tests).
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace sweepmap {

struct SpawnOptions {
  std::string log_path;          // stdout and stderr go there ("" = inherited)
  bool append_log = false;       // append (a restarted process) instead of truncating
  std::vector<std::string> env;  // "KEY=VALUE" set or replaced in the child's environment
  // The child leads a process group of its own: a terminal's Ctrl-C does not reach it, and
  // what it leaves behind when it dies can be killed with its group (killGroup).
  bool new_process_group = false;
  // Non-zero: the child gets this signal when its parent dies (PR_SET_PDEATHSIG), so that a
  // supervisor killed with SIGKILL leaves no process running behind it.
  int parent_death_signal = 0;
};

class ProcessGroup {
 public:
  ~ProcessGroup();  // SIGKILLs whatever is still running
  // Starts `argv` (argv[0] is searched in PATH); stdout/stderr go to `log_path` if set.
  pid_t start(const std::string& name, const std::vector<std::string>& argv,
              const std::string& log_path = "");
  pid_t start(const std::string& name, const std::vector<std::string>& argv,
              const SpawnOptions& options);
  // Waits up to timeout_s for `pid`; returns its exit status, or -1 on timeout.
  int wait(pid_t pid, double timeout_s);
  // SIGINT, then SIGKILL after grace_s; returns the exit status (128+signal if killed).
  int stop(pid_t pid, double grace_s);
  bool running(pid_t pid);
  const std::string& name(pid_t pid) const;
  // Sends `signal` to a child that has not been reaped.
  void signal(pid_t pid, int signal);
  // SIGKILLs what is left of the process group a child started with new_process_group led
  // (its own children: e.g. `sweepmap record`'s lcm-logger after the recorder was killed).
  static void killGroup(pid_t leader);
  // How a reaped child ended: "exit status N" or "killed by signal N (SIGNAME)".
  std::string describeExit(pid_t pid) const;

 private:
  struct Child {
    pid_t pid;
    std::string name;
    bool reaped = false;
    int status = 0;   // exit status, 128 + signal if killed
    int wstatus = 0;  // as waitpid gave it
  };
  Child* find(pid_t pid);
  std::vector<Child> children_;
};

// Runs a command to completion; returns its exit status (-1 if it could not start).
int runCommand(const std::vector<std::string>& argv, bool quiet = true);

}  // namespace sweepmap
