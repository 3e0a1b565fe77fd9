#include "tools/ops/process_group.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
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

pid_t spawn(const std::vector<std::string>& argv, const SpawnOptions& o, bool quiet) {
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
