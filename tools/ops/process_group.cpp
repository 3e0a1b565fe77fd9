#include "tools/ops/process_group.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace sweepmap {
namespace {

int decodeStatus(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

pid_t spawn(const std::vector<std::string>& argv, const std::string& log_path, bool quiet) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!log_path.empty()) {
    posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  } else if (quiet) {
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  }
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
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
  const pid_t pid = spawn(argv, log_path, false);
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
    return false;
  }
  return true;
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
  const pid_t pid = spawn(argv, "", quiet);
  if (pid < 0) return -1;
  int status = 0;
  if (::waitpid(pid, &status, 0) != pid) return -1;
  return decodeStatus(status);
}

}  // namespace sweepmap
