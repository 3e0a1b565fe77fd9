#include "tools/ops/netns.hpp"

#include <sched.h>

#include <cerrno>
#include <cstring>

#include "tools/ops/process_group.hpp"

namespace sweepmap {

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

}  // namespace sweepmap
