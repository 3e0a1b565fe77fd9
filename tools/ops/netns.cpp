#include "tools/ops/netns.hpp"

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <exception>
#include <stdexcept>

#include "tools/ops/process_group.hpp"

namespace sweepmap {
namespace {

// The calling thread's network namespace (a process's threads may be in different ones).
int openThreadNetns() { return ::open("/proc/thread-self/ns/net", O_RDONLY | O_CLOEXEC); }

std::string joined(const std::vector<std::string>& argv) {
  std::string s;
  for (const auto& a : argv) s += (s.empty() ? "" : " ") + a;
  return s;
}

}  // namespace

bool enterPrivateNetwork(std::string* why) {
  if (::unshare(CLONE_NEWNET) != 0) {
    *why = std::string("unshare(CLONE_NEWNET): ") + std::strerror(errno);
    return false;
  }
  for (const auto& cmd :
       {std::vector<std::string>{"ip", "link", "set", "lo", "up"},
        std::vector<std::string>{"ip", "route", "add", "224.0.0.0/4", "dev", "lo"}}) {
    if (runCommand(cmd) != 0) {
      *why = "'" + cmd[0] + " " + cmd[1] + " " + cmd[2] + " ...' failed in the new namespace";
      return false;
    }
  }
  return true;
}

std::unique_ptr<NetworkNamespace> NetworkNamespace::create(std::string* why) {
  const int home = openThreadNetns();
  if (home < 0) {
    *why = std::string("/proc/thread-self/ns/net: ") + std::strerror(errno);
    return nullptr;
  }
  if (::unshare(CLONE_NEWNET) != 0) {
    *why = std::string("unshare(CLONE_NEWNET): ") + std::strerror(errno);
    ::close(home);
    return nullptr;
  }
  const int fd = openThreadNetns();
  const int saved_errno = errno;
  const bool lo_up = fd >= 0 && runCommand({"ip", "link", "set", "lo", "up"}) == 0;
  if (::setns(home, CLONE_NEWNET) != 0) {
    // The thread is stranded in the new namespace: nothing it does from here is safe.
    throw std::runtime_error(std::string("setns back to the original network namespace: ") +
                             std::strerror(errno));
  }
  ::close(home);
  if (fd < 0) {
    *why = std::string("opening the new namespace: ") + std::strerror(saved_errno);
    return nullptr;
  }
  std::unique_ptr<NetworkNamespace> ns(new NetworkNamespace(fd));
  if (!lo_up) {
    *why = "'ip link set lo up' failed in the new namespace (is iproute2 installed?)";
    return nullptr;
  }
  return ns;
}

NetworkNamespace::~NetworkNamespace() { ::close(fd_); }

void NetworkNamespace::run(const std::function<void()>& fn) const {
  const int home = openThreadNetns();
  if (home < 0)
    throw std::runtime_error(std::string("/proc/thread-self/ns/net: ") + std::strerror(errno));
  if (::setns(fd_, CLONE_NEWNET) != 0) {
    const int e = errno;
    ::close(home);
    throw std::runtime_error(std::string("setns into a network namespace: ") + std::strerror(e));
  }
  std::exception_ptr error;
  try {
    fn();
  } catch (...) {
    error = std::current_exception();
  }
  const int rc = ::setns(home, CLONE_NEWNET);
  const int e = errno;
  ::close(home);
  if (rc != 0) {
    throw std::runtime_error(std::string("setns back to the original network namespace: ") +
                             std::strerror(e));
  }
  if (error) std::rethrow_exception(error);
}

int NetworkNamespace::command(const std::vector<std::string>& argv) const {
  int rc = -1;
  run([&] { rc = runCommand(argv); });
  return rc;
}

std::string NetworkNamespace::path() const {
  return "/proc/" + std::to_string(::getpid()) + "/fd/" + std::to_string(fd_);
}

bool joinByVeth(const NetworkNamespace& a, const VethEnd& end_a, const NetworkNamespace& b,
                const VethEnd& end_b, std::string* why) {
  // The pair is made in `a` with its peer created straight in `b`: it never appears in the
  // namespace this process runs in.
  const std::vector<std::string> add = {"ip",    "link", "add",  end_a.interface, "type",
                                        "veth",  "peer", "name", end_b.interface, "netns",
                                        b.path()};
  if (a.command(add) != 0) {
    *why = "'" + joined(add) + "' failed";
    return false;
  }
  for (const auto& [ns, end] : {std::pair{&a, &end_a}, std::pair{&b, &end_b}}) {
    for (const std::vector<std::string>& cmd :
         {std::vector<std::string>{"ip", "addr", "add", end->address, "dev", end->interface},
          std::vector<std::string>{"ip", "link", "set", end->interface, "up"},
          std::vector<std::string>{"ip", "route", "add", "224.0.0.0/4", "dev", end->interface}}) {
      if (ns->command(cmd) != 0) {
        *why = "'" + joined(cmd) + "' failed";
        return false;
      }
    }
  }
  return true;
}

}  // namespace sweepmap
