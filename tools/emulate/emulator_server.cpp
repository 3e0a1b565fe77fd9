#include "tools/emulate/emulator_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/inotify.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <vector>

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

using DeviceFactory = std::function<std::unique_ptr<EmulatedLidar>(int64_t now_us)>;

// One served device and its link (a TCP listener and client, or a pty), with the faults that
// are injected on it.
class EmulatorLink {
 public:
  EmulatorLink(const DeviceFactory& make_device, const ServerOptions& options,
               const LinkFaults& faults, const std::function<int64_t()>& now_us, std::ostream& info)
      : make_device_(make_device),
        options_(options),
        faults_(faults),
        now_us_(now_us),
        info_(info),
        rng_(faults.seed) {
    if (!options.pty) address_ = loopbackAddress(options.listen);
  }

  void run(const std::atomic<bool>& stop);

 private:
  void powerUp(int64_t now);
  void announcePty(const std::string& path);
  void powerDown(int64_t now);
  void waitForHost();
  void exchange();
  bool receive(std::string* out);
  void injectByteFaults(std::string* out);
  void transmit(const std::string& out);
  void noteTick(int64_t now);
  void reportLag(int64_t now);
  void reportUnread();
  void noteHostOpen();

  const DeviceFactory& make_device_;
  const ServerOptions& options_;
  const LinkFaults& faults_;
  const std::function<int64_t()>& now_us_;
  std::ostream& info_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::uniform_int_distribution<int> bit_{0, 7};
  sockaddr_in address_{};
  Fd listener_, client_, master_, slave_;
  std::unique_ptr<EmulatedLidar> device_;
  std::string pending_;  // TCP: bytes the client has not taken yet (bounded)
  int64_t start_us_ = 0;
  std::string out_;
  std::vector<uint8_t> in_ = std::vector<uint8_t>(4096);
  // Ticks the emulator could not run for (a machine too busy for it), since the last report.
  int64_t last_tick_us_ = -1;
  int64_t last_report_us_ = -1;
  int lags_ = 0;
  int64_t worst_lag_us_ = 0;
  bool burst_ = false;     // this tick sends what the device had to send while stalled
  size_t lost_bytes_ = 0;  // of those bursts, the bytes the link's buffer had no room for
  // Bytes a pty had no room for outside a burst, before a host opened it (it started late) and
  // after (it did not read in time): a real UART drops them the same way.
  size_t unread_bytes_ = 0, unread_before_host_ = 0;
  // Whether a host has opened the pty: inotify's IN_OPEN on its path (our own end was opened
  // before the watch). Where the watch cannot be set, the losses are not split.
  Fd opens_;
  bool host_opened_ = false;
};

// A gap between two ticks longer than this: the emulator did not keep real time.
constexpr int64_t kLagUs = 100000;
// At most one report per this much time (the rest are counted into the next one).
constexpr int64_t kLagReportUs = 5000000;

void EmulatorLink::run(const std::atomic<bool>& stop) {
  start_us_ = now_us_();
  powerUp(start_us_);
  bool hung_up = false;
  int64_t down_until = -1;
  while (!stop) {
    const int64_t now = now_us_();
    noteTick(now);
    const double elapsed_s = static_cast<double>(now - start_us_) * 1e-6;
    if (options_.duration_s > 0 && elapsed_s >= options_.duration_s) break;
    if (!hung_up && faults_.hangup_at_s >= 0 && elapsed_s >= faults_.hangup_at_s) {
      hung_up = true;
      powerDown(now);
      down_until = now + static_cast<int64_t>(faults_.down_s * 1e6);
      info_ << "emulator: hang-up injected; back in " << faults_.down_s << " s" << std::endl;
    }
    if (!device_) {
      if (now >= down_until) {
        powerUp(now);
      } else {
        ::usleep(static_cast<useconds_t>(options_.tick_us));
      }
      continue;
    }
    if (!options_.pty && !client_) {
      waitForHost();
      continue;
    }
    exchange();
  }
  if (lags_ > 0) reportLag(now_us_());
  if (unread_bytes_ + unread_before_host_ > 0) reportUnread();
  powerDown(now_us_());
}

// A tick that comes long after the last one means the emulator was not running in between
// (the machine is too busy): the device's bytes of that time go out at once, in a burst that
// a serial buffer may not hold. Said on `info` after the burst's tick (so that it counts what
// the burst lost), so that the host's errors are not taken for the driver's. A TCP device
// with no host sends nowhere: its stalls harm nobody and are not counted.
void EmulatorLink::noteTick(int64_t now) {
  burst_ = false;
  if (last_tick_us_ >= 0 && now - last_tick_us_ > kLagUs && (options_.pty || client_)) {
    ++lags_;
    worst_lag_us_ = std::max(worst_lag_us_, now - last_tick_us_);
    burst_ = true;
  }
  last_tick_us_ = now;
  if (lags_ > 0 && !burst_ && (last_report_us_ < 0 || now - last_report_us_ >= kLagReportUs)) {
    reportLag(now);
  }
}

// Said once, at the end, split at the host's opening of the pty: bytes lost before it mean a
// host that started late (or never), bytes lost after it a host that did not read in time.
void EmulatorLink::reportUnread() {
  info_ << "emulator: the pty had no room for " << unread_before_host_ + unread_bytes_
        << " of the bytes the device sent";
  if (opens_) {
    info_ << ": " << unread_before_host_ << " before a host opened it (it started late, or never), "
          << unread_bytes_
          << " after (the host did not read in time: a real UART drops them the same way)";
  } else {
    info_ << " (while no host had it open, or while the host did not read in time: a real UART "
             "drops them the same way)";
  }
  info_ << std::endl;
  unread_bytes_ = unread_before_host_ = 0;
}

// Whether a host has opened the pty since the last look (inotify's IN_OPEN on its path).
void EmulatorLink::noteHostOpen() {
  if (!opens_ || host_opened_) return;
  alignas(inotify_event) char buf[4096];
  for (ssize_t n; (n = ::read(opens_.fd, buf, sizeof buf)) > 0;) host_opened_ = true;
}

void EmulatorLink::reportLag(int64_t now) {
  std::ostringstream seconds;
  seconds << std::fixed << std::setprecision(2) << 1e-6 * double(worst_lag_us_);
  info_ << "emulator: could not keep real time: stalled " << lags_
        << (lags_ == 1 ? " time" : " times") << ", for up to " << seconds.str()
        << " s (the machine is too busy for it); the device's bytes of that time went out at once";
  if (lost_bytes_ > 0) info_ << ", " << lost_bytes_ << " of them lost (the link's buffer was full)";
  info_ << "; the host's errors and time jumps around then are the emulator's, not the device's"
        << std::endl;
  last_report_us_ = now;
  lags_ = 0;
  worst_lag_us_ = 0;
  lost_bytes_ = 0;
}

void EmulatorLink::powerUp(int64_t now) {
  device_ = make_device_(now);
  if (options_.pty) {
    const std::string path = openPty(&master_, &slave_);
    host_opened_ = false;  // a new pty: nobody has opened it
    opens_.reset(::inotify_init1(IN_NONBLOCK | IN_CLOEXEC));
    if (opens_ && ::inotify_add_watch(opens_.fd, path.c_str(), IN_OPEN) < 0) opens_.reset(-1);
    announcePty(path);
  } else {
    listener_.reset(listenOn(address_, options_.listen));
    info_ << "emulator: listening on " << options_.listen << std::endl;
  }
}

// Prints the new pty's path, through the link the options ask for.
void EmulatorLink::announcePty(const std::string& path) {
  if (options_.pty_link.empty()) {
    info_ << "emulator: serial device at " << path << std::endl;
    return;
  }
  ::unlink(options_.pty_link.c_str());
  if (::symlink(path.c_str(), options_.pty_link.c_str()) < 0) {
    throw std::runtime_error("cannot link " + options_.pty_link + " -> " + path + ": " +
                             std::strerror(errno));
  }
  info_ << "emulator: serial device at " << options_.pty_link << " (-> " << path << ")"
        << std::endl;
}

void EmulatorLink::powerDown(int64_t now) {
  client_.reset();
  listener_.reset();
  master_.reset();
  slave_.reset();
  pending_.clear();
  if (options_.pty && !options_.pty_link.empty()) ::unlink(options_.pty_link.c_str());
  if (device_) device_->reset(now);
  device_.reset();
}

// TCP with no host: accepts one if it comes within a tick; the device's time passes anyway.
void EmulatorLink::waitForHost() {
  pollfd p{listener_.fd, POLLIN, 0};
  if (::poll(&p, 1, options_.tick_us / 1000 + 1) > 0) {
    const int c = ::accept4(listener_.fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (c >= 0) {
      const int one = 1;
      ::setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      client_.reset(c);
      device_->reset(now_us_());  // a new TCP session starts from the power-on state
      info_ << "emulator: host connected" << std::endl;
    }
  }
  out_.clear();
  device_->advance(now_us_(), &out_);  // time passes for the device either way
}

// One tick with a host: what it sent goes to the device, what the device says goes back.
void EmulatorLink::exchange() {
  out_.clear();
  if (!receive(&out_)) return;
  device_->advance(now_us_(), &out_);
  const double t_s = static_cast<double>(now_us_() - start_us_) * 1e-6;
  if (faults_.stall_at_s >= 0 && t_s >= faults_.stall_at_s &&
      t_s < faults_.stall_at_s + faults_.stall_s) {
    out_.clear();  // stalled: what the device sends now is lost
  }
  injectByteFaults(&out_);
  if (out_.empty() && pending_.empty()) return;
  transmit(out_);
}

// Waits up to a tick for the host's bytes and hands them to the device; false when the TCP
// host went away (the device is then back in its power-on state).
bool EmulatorLink::receive(std::string* out) {
  const int io_fd = options_.pty ? master_.fd : client_.fd;
  pollfd p{io_fd, POLLIN, 0};
  const int ready = ::poll(&p, 1, options_.tick_us / 1000 + 1);
  if (ready <= 0 || !(p.revents & (POLLIN | POLLHUP | POLLERR))) return true;
  const ssize_t n = ::read(io_fd, in_.data(), in_.size());
  if (n > 0) {
    device_->receive(in_.data(), static_cast<size_t>(n), now_us_(), out);
  } else if (!options_.pty && (n == 0 || (errno != EAGAIN && errno != EINTR))) {
    client_.reset();  // the host went away
    pending_.clear();
    device_->reset(now_us_());
    info_ << "emulator: host disconnected" << std::endl;
    return false;
  }
  return true;
}

void EmulatorLink::injectByteFaults(std::string* out) {
  if (faults_.corrupt_rate <= 0) return;
  for (char& c : *out) {
    if (uniform_(rng_) < faults_.corrupt_rate) c = static_cast<char>(c ^ (1 << bit_(rng_)));
  }
}

void EmulatorLink::transmit(const std::string& out) {
  if (options_.pty) {
    // A UART sends whether or not anybody reads: what does not fit is lost.
    const ssize_t n = ::write(master_.fd, out.data(), out.size());
    const size_t lost = out.size() - static_cast<size_t>(std::max<ssize_t>(n, 0));
    if (lost > 0) noteHostOpen();
    (burst_ ? lost_bytes_ : host_opened_ || !opens_ ? unread_bytes_ : unread_before_host_) += lost;
    return;
  }
  pending_ += out;
  if (pending_.size() > (4u << 20)) {
    if (burst_) lost_bytes_ += pending_.size() - (4u << 20);
    pending_.erase(0, pending_.size() - (4u << 20));
  }
  const ssize_t n = ::send(client_.fd, pending_.data(), pending_.size(), MSG_NOSIGNAL);
  if (n > 0) pending_.erase(0, static_cast<size_t>(n));
}

}  // namespace

void serveEmulator(const DeviceFactory& make_device, const ServerOptions& options,
                   const LinkFaults& faults, const std::function<int64_t()>& now_us,
                   const std::atomic<bool>& stop, std::ostream& info) {
  if (options.pty == !options.listen.empty()) {
    throw std::runtime_error("serve either --listen HOST:PORT or --pty");
  }
  EmulatorLink(make_device, options, faults, now_us, info).run(stop);
}

}  // namespace sweepmap
