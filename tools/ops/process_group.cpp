#include "tools/ops/process_group.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>

extern char** environ;

namespace sweepmap {
namespace {

int decodeStatus(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

// The parent's environment with `overrides` ("KEY=VALUE") set or replaced.
std::vector<std::string> environment(const std::vector<std::string>& overrides) {
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry = *e;
    const std::string key = entry.substr(0, entry.find('=') + 1);
    bool replaced = false;
    for (const auto& o : overrides) replaced = replaced || o.rfind(key, 0) == 0;
    if (!replaced) env.push_back(entry);
  }
  env.insert(env.end(), overrides.begin(), overrides.end());
  return env;
}

// argv[0] as execvp would find it, or "" when it is nowhere in PATH.
std::string resolve(const std::string& program) {
  if (program.find('/') != std::string::npos)
    return ::access(program.c_str(), X_OK) == 0 ? program : "";
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    const std::string candidate =
        (end > start ? dirs.substr(start, end - start) : std::string(".")) + "/" + program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return "";
}

// fork and exec, for what posix_spawn cannot set (the parent-death signal). Everything the
// child needs is made before the fork: between fork and exec it only calls what is safe in
// a child of a threaded process.
pid_t forkExec(const std::vector<std::string>& argv, const SpawnOptions& o, char** envp) {
  const std::string program = resolve(argv[0]);
  if (program.empty()) return -1;
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t parent = ::getpid();
  const int log_flags = O_WRONLY | O_CREAT | (o.append_log ? O_APPEND : O_TRUNC) | O_CLOEXEC;
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  ::prctl(PR_SET_PDEATHSIG, o.parent_death_signal);
  if (::getppid() != parent) ::_exit(127);  // the parent died before prctl
  if (o.new_process_group) ::setpgid(0, 0);
  if (!o.log_path.empty()) {
    const int fd = ::open(o.log_path.c_str(), log_flags, 0644);
    if (fd < 0 || ::dup2(fd, 1) < 0 || ::dup2(fd, 2) < 0) ::_exit(127);
  }
  sigset_t none;
  sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  ::execve(program.c_str(), args.data(), envp);
  ::_exit(127);
}

pid_t spawn(const std::vector<std::string>& argv, const SpawnOptions& o, bool quiet) {
  if (o.parent_death_signal != 0 && !quiet) {
    std::vector<std::string> env_strings = environment(o.env);
    std::vector<char*> env;
    for (auto& e : env_strings) env.push_back(e.data());
    env.push_back(nullptr);
    return forkExec(argv, o, env.data());
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string& log_path = o.log_path;
  if (!log_path.empty()) {
    posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(),
                                     O_WRONLY | O_CREAT | (o.append_log ? O_APPEND : O_TRUNC),
                                     0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  } else if (quiet) {
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  }
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<std::string> env_strings;
  std::vector<char*> env;
  char** envp = environ;
  if (!o.env.empty()) {
    env_strings = environment(o.env);
    for (auto& e : env_strings) env.push_back(e.data());
    env.push_back(nullptr);
    envp = env.data();
  }
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  if (o.new_process_group) {
    posix_spawnattr_setpgroup(&attr, 0);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  }
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, args[0], &actions, &attr, args.data(), envp);
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&actions);
  return rc == 0 ? pid : -1;
}

}  // namespace

ProcessGroup::~ProcessGroup() {
  for (auto& c : children_) {
    if (!c.reaped) {
      ::kill(c.pid, SIGKILL);
      ::waitpid(c.pid, nullptr, 0);
    }
  }
}

pid_t ProcessGroup::start(const std::string& name, const std::vector<std::string>& argv,
                          const std::string& log_path) {
  SpawnOptions o;
  o.log_path = log_path;
  return start(name, argv, o);
}

pid_t ProcessGroup::start(const std::string& name, const std::vector<std::string>& argv,
                          const SpawnOptions& options) {
  const pid_t pid = spawn(argv, options, false);
  if (pid < 0) throw std::runtime_error("cannot start " + name + " (" + argv[0] + ")");
  children_.push_back({pid, name});
  return pid;
}

ProcessGroup::Child* ProcessGroup::find(pid_t pid) {
  for (auto& c : children_) {
    if (c.pid == pid) return &c;
  }
  return nullptr;
}

const std::string& ProcessGroup::name(pid_t pid) const {
  static const std::string unknown = "?";
  for (const auto& c : children_) {
    if (c.pid == pid) return c.name;
  }
  return unknown;
}

bool ProcessGroup::running(pid_t pid) {
  Child* c = find(pid);
  if (!c || c->reaped) return false;
  int status = 0;
  if (::waitpid(pid, &status, WNOHANG) == pid) {
    c->reaped = true;
    c->status = decodeStatus(status);
    c->wstatus = status;
    return false;
  }
  return true;
}

void ProcessGroup::signal(pid_t pid, int signal) {
  const Child* c = find(pid);
  if (c && !c->reaped) ::kill(pid, signal);
}

void ProcessGroup::killGroup(pid_t leader) {
  if (leader > 0) ::kill(-leader, SIGKILL);
}

std::string ProcessGroup::describeExit(pid_t pid) const {
  for (const auto& c : children_) {
    if (c.pid != pid) continue;
    if (!c.reaped) return "running";
    if (WIFSIGNALED(c.wstatus)) {
      const int sig = WTERMSIG(c.wstatus);
      const char* name = sigabbrev_np(sig);
      return "killed by signal " + std::to_string(sig) +
             (name ? std::string(" (SIG") + name + ")" : "");
    }
    return "exit status " + std::to_string(c.status);
  }
  return "unknown";
}

int ProcessGroup::wait(pid_t pid, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::milliseconds(static_cast<int64_t>(timeout_s * 1000));
  while (running(pid)) {
    if (std::chrono::steady_clock::now() > deadline) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  Child* c = find(pid);
  return c ? c->status : -1;
}

int ProcessGroup::stop(pid_t pid, double grace_s) {
  if (!running(pid)) {
    Child* c = find(pid);
    return c ? c->status : -1;
  }
  ::kill(pid, SIGINT);
  const int rc = wait(pid, grace_s);
  if (rc != -1) return rc;
  ::kill(pid, SIGKILL);
  return wait(pid, 5.0);
}

int runCommand(const std::vector<std::string>& argv, bool quiet) {
  const pid_t pid = spawn(argv, SpawnOptions{}, quiet);
  if (pid < 0) return -1;
  int status = 0;
  if (::waitpid(pid, &status, 0) != pid) return -1;
  return decodeStatus(status);
}

}  // namespace sweepmap
