// Starting, stopping and waiting for child processes (used by `sweepmap demo` and tests).
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace sweepmap {

class ProcessGroup {
 public:
  ~ProcessGroup();  // SIGKILLs whatever is still running
  // Starts `argv` (argv[0] is searched in PATH); stdout/stderr go to `log_path` if set.
  pid_t start(const std::string& name, const std::vector<std::string>& argv,
              const std::string& log_path = "");
  // Waits up to timeout_s for `pid`; returns its exit status, or -1 on timeout.
  int wait(pid_t pid, double timeout_s);
  // SIGINT, then SIGKILL after grace_s; returns the exit status (128+signal if killed).
  int stop(pid_t pid, double grace_s);
  bool running(pid_t pid);
  const std::string& name(pid_t pid) const;

 private:
  struct Child {
    pid_t pid;
    std::string name;
    bool reaped = false;
    int status = 0;
  };
  Child* find(pid_t pid);
  std::vector<Child> children_;
};

// Runs a command to completion; returns its exit status (-1 if it could not start).
int runCommand(const std::vector<std::string>& argv, bool quiet = true);

}  // namespace sweepmap
