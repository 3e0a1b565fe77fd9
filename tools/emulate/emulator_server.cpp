#include "tools/emulate/emulator_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace sweepmap {
namespace {

struct Fd {
  int fd = -1;
  Fd() = default;
  explicit Fd(int f) : fd(f) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() { reset(); }
  void reset(int f = -1) {
    if (fd >= 0) ::close(fd);
    fd = f;
  }
  explicit operator bool() const { return fd >= 0; }
};

sockaddr_in loopbackAddress(const std::string& listen) {
  const size_t colon = listen.rfind(':');
  if (colon == std::string::npos) {
    throw std::runtime_error("--listen '" + listen + "': expected HOST:PORT");
  }
  std::string host = listen.substr(0, colon);
  if (host == "localhost") host = "127.0.0.1";
  sockaddr_in a{};
  a.sin_family = AF_INET;
  if (::inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1) {
    throw std::runtime_error("--listen '" + listen + "': not an IPv4 address");
  }
  // Loopback only: an emulator never serves another machine.
  if ((ntohl(a.sin_addr.s_addr) >> 24) != 127) {
    throw std::runtime_error("--listen '" + listen + "': only loopback (127.0.0.0/8) is allowed");
  }
  int port = 0;
  try {
    port = std::stoi(listen.substr(colon + 1));
  } catch (const std::exception&) {
    port = -1;
  }
  if (port <= 0 || port > 65535) throw std::runtime_error("--listen '" + listen + "': bad port");
  a.sin_port = htons(static_cast<uint16_t>(port));
  return a;
}

int listenOn(const sockaddr_in& a, const std::string& listen) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("socket: " + std::string(std::strerror(errno)));
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) < 0 || ::listen(fd, 1) < 0) {
    const int err = errno;
    ::close(fd);
    throw std::runtime_error("cannot listen on " + listen + ": " + std::strerror(err));
  }
  return fd;
}

// A new pty: the master for us, its slave kept open (raw) so that the link stays up while
// no host has it open; returns the slave's path.
std::string openPty(Fd* master, Fd* slave) {
  const int m = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (m < 0 || ::grantpt(m) < 0 || ::unlockpt(m) < 0) {
    throw std::runtime_error("cannot create a pseudo-terminal: " +
                             std::string(std::strerror(errno)));
  }
  master->reset(m);
  const char* name = ::ptsname(m);
  if (!name) throw std::runtime_error("ptsname: " + std::string(std::strerror(errno)));
  const std::string path = name;
  const int s = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (s < 0) throw std::runtime_error("cannot open " + path + ": " + std::strerror(errno));
  termios t{};
  ::tcgetattr(s, &t);
  ::cfmakeraw(&t);
  ::tcsetattr(s, TCSANOW, &t);
  slave->reset(s);
  return path;
}

}  // namespace

void serveEmulator(const std::function<std::unique_ptr<EmulatedLidar>(int64_t now_us)>& make_device,
                   const ServerOptions& options, const LinkFaults& faults,
                   const std::function<int64_t()>& now_us, const std::atomic<bool>& stop,
                   std::ostream& info) {
  if (options.pty == !options.listen.empty()) {
    throw std::runtime_error("serve either --listen HOST:PORT or --pty");
  }
  std::mt19937_64 rng(faults.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::uniform_int_distribution<int> bit(0, 7);
  sockaddr_in address{};
  if (!options.pty) address = loopbackAddress(options.listen);

  Fd listener, client, master, slave;
  std::unique_ptr<EmulatedLidar> device;
  std::string pending;  // TCP: bytes the client has not taken yet (bounded)
  const auto powerUp = [&](int64_t now) {
    device = make_device(now);
    if (options.pty) {
      const std::string path = openPty(&master, &slave);
      if (!options.pty_link.empty()) {
        ::unlink(options.pty_link.c_str());
        if (::symlink(path.c_str(), options.pty_link.c_str()) < 0) {
          throw std::runtime_error("cannot link " + options.pty_link + " -> " + path + ": " +
                                   std::strerror(errno));
        }
        info << "emulator: serial device at " << options.pty_link << " (-> " << path << ")"
             << std::endl;
      } else {
        info << "emulator: serial device at " << path << std::endl;
      }
    } else {
      listener.reset(listenOn(address, options.listen));
      info << "emulator: listening on " << options.listen << std::endl;
    }
  };
  const auto powerDown = [&](int64_t now) {
    client.reset();
    listener.reset();
    master.reset();
    slave.reset();
    pending.clear();
    if (options.pty && !options.pty_link.empty()) ::unlink(options.pty_link.c_str());
    if (device) device->reset(now);
    device.reset();
  };

  const int64_t start = now_us();
  powerUp(start);
  bool hung_up = false;
  int64_t down_until = -1;
  std::string out;
  std::vector<uint8_t> in(4096);
  while (!stop) {
    const int64_t now = now_us();
    const double elapsed_s = static_cast<double>(now - start) * 1e-6;
    if (options.duration_s > 0 && elapsed_s >= options.duration_s) break;
    if (!hung_up && faults.hangup_at_s >= 0 && elapsed_s >= faults.hangup_at_s) {
      hung_up = true;
      powerDown(now);
      down_until = now + static_cast<int64_t>(faults.down_s * 1e6);
      info << "emulator: hang-up injected; back in " << faults.down_s << " s" << std::endl;
    }
    if (!device) {
      if (now >= down_until) {
        powerUp(now);
      } else {
        ::usleep(static_cast<useconds_t>(options.tick_us));
      }
      continue;
    }
    if (!options.pty && !client) {
      pollfd p{listener.fd, POLLIN, 0};
      if (::poll(&p, 1, options.tick_us / 1000 + 1) > 0) {
        const int c = ::accept4(listener.fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (c >= 0) {
          const int one = 1;
          ::setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
          client.reset(c);
          device->reset(now_us());  // a new TCP session starts from the power-on state
          info << "emulator: host connected" << std::endl;
        }
      }
      out.clear();
      device->advance(now_us(), &out);  // time passes for the device either way
      continue;
    }
    const int io_fd = options.pty ? master.fd : client.fd;
    pollfd p{io_fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, options.tick_us / 1000 + 1);
    out.clear();
    if (ready > 0 && (p.revents & (POLLIN | POLLHUP | POLLERR))) {
      const ssize_t n = ::read(io_fd, in.data(), in.size());
      if (n > 0) {
        device->receive(in.data(), static_cast<size_t>(n), now_us(), &out);
      } else if (!options.pty && (n == 0 || (errno != EAGAIN && errno != EINTR))) {
        client.reset();  // the host went away
        pending.clear();
        device->reset(now_us());
        info << "emulator: host disconnected" << std::endl;
        continue;
      }
    }
    device->advance(now_us(), &out);
    const double t_s = static_cast<double>(now_us() - start) * 1e-6;
    if (faults.stall_at_s >= 0 && t_s >= faults.stall_at_s &&
        t_s < faults.stall_at_s + faults.stall_s) {
      out.clear();  // stalled: what the device sends now is lost
    }
    if (faults.corrupt_rate > 0) {
      for (char& c : out) {
        if (uniform(rng) < faults.corrupt_rate) c = static_cast<char>(c ^ (1 << bit(rng)));
      }
    }
    if (out.empty() && pending.empty()) continue;
    if (options.pty) {
      // A UART sends whether or not anybody reads: what does not fit is lost.
      (void)!::write(master.fd, out.data(), out.size());
    } else {
      pending += out;
      if (pending.size() > (4u << 20)) pending.erase(0, pending.size() - (4u << 20));
      const ssize_t n = ::send(client.fd, pending.data(), pending.size(), MSG_NOSIGNAL);
      if (n > 0) pending.erase(0, static_cast<size_t>(n));
    }
  }
  powerDown(now_us());
}

}  // namespace sweepmap
