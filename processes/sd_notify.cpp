#include "processes/sd_notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstddef>
#include <cstdlib>
#include <cstring>

namespace sweepmap {

bool sdNotify(const std::string& state) {
  const char* path = std::getenv("NOTIFY_SOCKET");
  if (path == nullptr || (path[0] != '/' && path[0] != '@')) return false;
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const size_t length = std::strlen(path);
  if (length >= sizeof(addr.sun_path)) return false;
  std::memcpy(addr.sun_path, path, length);
  if (path[0] == '@') addr.sun_path[0] = '\0';  // abstract: no terminating NUL counted
  const socklen_t addr_len =
      static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + length + (path[0] == '@' ? 0 : 1));
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  const ssize_t sent = ::sendto(fd, state.data(), state.size(), MSG_NOSIGNAL | MSG_DONTWAIT,
                                reinterpret_cast<const sockaddr*>(&addr), addr_len);
  ::close(fd);
  return sent == static_cast<ssize_t>(state.size());
}

int64_t sdWatchdogUsec() {
  const char* usec = std::getenv("WATCHDOG_USEC");
  if (usec == nullptr) return 0;
  if (const char* pid = std::getenv("WATCHDOG_PID")) {
    if (std::strtoll(pid, nullptr, 10) != static_cast<long long>(::getpid())) return 0;
  }
  char* end = nullptr;
  const long long v = std::strtoll(usec, &end, 10);
  return (end != usec && *end == '\0' && v > 0) ? v : 0;
}

SdNotifier::SdNotifier()
    : enabled_(std::getenv("NOTIFY_SOCKET") != nullptr),
      interval_(std::chrono::microseconds(sdWatchdogUsec() / 2)) {}

void SdNotifier::ready() {
  if (!enabled_) return;
  sdNotify("READY=1");
  last_ping_ = std::chrono::steady_clock::now();
}

void SdNotifier::alive(std::chrono::steady_clock::time_point now) {
  if (!enabled_ || interval_.count() <= 0 || now - last_ping_ < interval_) return;
  sdNotify("WATCHDOG=1");
  last_ping_ = now;
}

void SdNotifier::stopping() {
  if (enabled_) sdNotify("STOPPING=1");
}

}  // namespace sweepmap
