#include "drivers/io/byte_stream.hpp"

#include <arpa/inet.h>
#include <asm/termbits.h>  // termios2 / BOTHER: any baud rate (the X4's 128000)
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

namespace sweepmap {
namespace {

int64_t monotonicMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::string errnoText(int err) { return std::strerror(err); }

// One file descriptor, closed on destruction; reads and writes through poll(2).
class FdStream : public ByteStream {
 public:
  FdStream(int fd, std::string description) : fd_(fd), description_(std::move(description)) {}
  ~FdStream() override {
    if (fd_ >= 0) ::close(fd_);
  }
  FdStream(const FdStream&) = delete;
  FdStream& operator=(const FdStream&) = delete;

  size_t read(uint8_t* buffer, size_t capacity, int timeout_ms) override {
    pollfd p{fd_, POLLIN, 0};
    int r;
    do {
      r = ::poll(&p, 1, timeout_ms);
    } while (r < 0 && errno == EINTR);
    if (r < 0) throw StreamError(description_ + ": poll: " + errnoText(errno));
    if (r == 0) return 0;
    if (p.revents & POLLNVAL) throw StreamError(description_ + ": closed descriptor");
    // Read what is there even when POLLHUP came with it: the last bytes before a hang-up
    // are data like any other.
    ssize_t n;
    do {
      n = ::read(fd_, buffer, capacity);
    } while (n < 0 && errno == EINTR);
    if (n > 0) return static_cast<size_t>(n);
    if (n == 0) throw StreamError(description_ + ": hang-up (end of stream)");
    if (errno == EAGAIN || errno == EWOULDBLOCK) {
      if (p.revents & (POLLHUP | POLLERR)) throw StreamError(description_ + ": hang-up");
      return 0;
    }
    // A pty whose other side closed reads EIO: a hang-up.
    if (errno == EIO) throw StreamError(description_ + ": hang-up (I/O error)");
    throw StreamError(description_ + ": read: " + errnoText(errno));
  }

  void write(const void* data, size_t size, int timeout_ms) override {
    const auto* p = static_cast<const uint8_t*>(data);
    const int64_t deadline = monotonicMs() + timeout_ms;
    while (size > 0) {
      const ssize_t n = send_or_write(p, size);
      if (n > 0) {
        p += n;
        size -= static_cast<size_t>(n);
        continue;
      }
      if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        throw StreamError(description_ + ": write: " + errnoText(errno));
      }
      const int64_t left = deadline - monotonicMs();
      if (left <= 0) throw StreamError(description_ + ": write timed out");
      pollfd q{fd_, POLLOUT, 0};
      ::poll(&q, 1, static_cast<int>(left));
      if (q.revents & (POLLHUP | POLLERR | POLLNVAL)) {
        throw StreamError(description_ + ": hang-up while writing");
      }
    }
  }

  int fd() const override { return fd_; }
  std::string describe() const override { return description_; }

 protected:
  virtual ssize_t send_or_write(const uint8_t* p, size_t n) { return ::write(fd_, p, n); }
  int fd_;
  std::string description_;
};

class TcpStream : public FdStream {
 public:
  using FdStream::FdStream;

 protected:
  // MSG_NOSIGNAL: a peer that went away is an error here, not a SIGPIPE for the process.
  ssize_t send_or_write(const uint8_t* p, size_t n) override {
    return ::send(fd_, p, n, MSG_NOSIGNAL);
  }
};

class SerialStream : public FdStream {
 public:
  using FdStream::FdStream;
  void setDtr(bool on) override {
    int bits = TIOCM_DTR;
    // A pseudo-terminal has no modem lines (ENOTTY/EINVAL): nothing to switch.
    (void)::ioctl(fd_, on ? TIOCMBIS : TIOCMBIC, &bits);
  }
};

}  // namespace

void ByteStream::drain(int quiet_ms) {
  uint8_t buffer[4096];
  while (read(buffer, sizeof buffer, quiet_ms) > 0) {
  }
}

std::unique_ptr<ByteStream> openTcp(const std::string& host, int port, int timeout_ms) {
  const std::string where = "tcp " + host + ":" + std::to_string(port);
  if (port <= 0 || port > 65535) throw StreamError(where + ": bad port");
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int gai = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found);
  if (gai != 0) throw StreamError(where + ": " + ::gai_strerror(gai));
  std::string last_error = "no address";
  for (addrinfo* a = found; a; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) {
      last_error = errnoText(errno);
      continue;
    }
    int err = 0;
    if (::connect(fd, a->ai_addr, a->ai_addrlen) < 0) {
      err = errno;
      if (err == EINPROGRESS) {
        pollfd p{fd, POLLOUT, 0};
        const int r = ::poll(&p, 1, timeout_ms);
        if (r == 0) {
          err = ETIMEDOUT;
        } else {
          socklen_t len = sizeof err;
          ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
        }
      }
    }
    if (err == 0) {
      const int one = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      ::freeaddrinfo(found);
      return std::make_unique<TcpStream>(fd, where);
    }
    last_error = errnoText(err);
    ::close(fd);
  }
  ::freeaddrinfo(found);
  throw StreamError(where + ": " + last_error);
}

std::unique_ptr<ByteStream> openSerial(const std::string& path, int baud) {
  const std::string where = "serial " + path;
  if (baud <= 0) throw StreamError(where + ": bad baud rate " + std::to_string(baud));
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw StreamError(where + ": " + errnoText(errno));
  termios2 tio{};
  if (::ioctl(fd, TCGETS2, &tio) < 0) {
    const int err = errno;
    ::close(fd);
    throw StreamError(where + ": not a serial port (" + errnoText(err) + ")");
  }
  // Raw 8N1, no flow control, no echo, no line discipline; any baud rate (BOTHER).
  tio.c_iflag &= ~(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON | IXOFF);
  tio.c_oflag &= ~OPOST;
  tio.c_lflag &= ~(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
  tio.c_cflag &= ~(CSIZE | PARENB | CSTOPB | CRTSCTS | CBAUD);
  tio.c_cflag |= CS8 | CLOCAL | CREAD | BOTHER;
  tio.c_ispeed = static_cast<speed_t>(baud);
  tio.c_ospeed = static_cast<speed_t>(baud);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (::ioctl(fd, TCSETS2, &tio) < 0) {
    const int err = errno;
    ::close(fd);
    throw StreamError(where + ": cannot set " + std::to_string(baud) + " baud 8N1 (" +
                      errnoText(err) + ")");
  }
  ::ioctl(fd, TCFLSH, TCIOFLUSH);
  return std::make_unique<SerialStream>(fd, where + " @" + std::to_string(baud));
}

}  // namespace sweepmap
