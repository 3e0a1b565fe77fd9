// A private network namespace for live LCM runs: nothing leaves this machine, and runs
// in parallel do not hear each other.
#pragma once

#include <string>

namespace sweepmap {

// Moves this process (and the children it starts afterwards) into a new network
// namespace with `lo` up and 224.0.0.0/4 routed to it. Returns false with the reason
// when namespaces are unavailable (no CAP_SYS_ADMIN, no `ip`).
bool enterPrivateNetwork(std::string* why);

}  // namespace sweepmap
