// Private network namespaces for live LCM runs: nothing leaves this machine, and runs in
// parallel do not hear each other. Two of them joined by a veth pair stand for two hosts
// (the Pi and the laptop) on one link.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace sweepmap {

// Moves this process (and the children it starts afterwards) into a new network
// namespace with `lo` up and 224.0.0.0/4 routed to it. Returns false with the reason
// when namespaces are unavailable (no CAP_SYS_ADMIN, no `ip`).
bool enterPrivateNetwork(std::string* why);

// A network namespace held by a file descriptor: no name under /var/run/netns (none is
// needed, none is left behind), gone when this object and the last process in it are.
class NetworkNamespace {
 public:
  // A new namespace with `lo` up; nullptr with the reason when namespaces are unavailable.
  static std::unique_ptr<NetworkNamespace> create(std::string* why);
  ~NetworkNamespace();
  NetworkNamespace(const NetworkNamespace&) = delete;
  NetworkNamespace& operator=(const NetworkNamespace&) = delete;

  // Calls `fn` with the calling thread inside this namespace, then returns it to the one it
  // was in (also when `fn` throws). Processes started in `fn` (ProcessGroup::start,
  // runCommand) stay in this namespace for their life. Throws std::runtime_error when the
  // thread cannot switch.
  void run(const std::function<void()>& fn) const;
  // Runs `argv` to completion in this namespace (quiet); returns its exit status.
  int command(const std::vector<std::string>& argv) const;
  // A path naming this namespace to other processes: `ip link ... netns PATH`,
  // `nsenter --net=PATH`.
  std::string path() const;

 private:
  explicit NetworkNamespace(int fd) : fd_(fd) {}
  int fd_;
};

// One end of a veth link: its interface name and address with prefix ("10.77.0.1/24").
struct VethEnd {
  std::string interface;
  std::string address;
};

// Joins `a` and `b` by a veth pair, both ends up with their addresses, and routes
// 224.0.0.0/4 to the veth on each side, so LCM multicast with ttl=1 crosses the link as
// it crosses an Ethernet segment. Returns false with the failing command.
bool joinByVeth(const NetworkNamespace& a, const VethEnd& end_a, const NetworkNamespace& b,
                const VethEnd& end_b, std::string* why);

}  // namespace sweepmap
