#include "net/udpm_receiver.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace sweepmap::net {
namespace {

constexpr const char* kLiblcmDefaultUrl = "udpm://239.255.76.67:7667?ttl=0";
// One byte more than the largest UDP payload: a datagram that fills it was truncated.
constexpr size_t kReceiveBufferBytes = 65536;

int parseInt(const std::string& url, const std::string& what, const std::string& text, long lo,
             long hi) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || v < lo || v > hi) {
    throw std::invalid_argument("LCM URL '" + url + "': " + what + " '" + text +
                                "' is not an integer in " + std::to_string(lo) + ".." +
                                std::to_string(hi));
  }
  return static_cast<int>(v);
}

void parseOptions(const std::string& url, const std::string& query, UdpmUrl& u) {
  size_t start = 0;
  while (start < query.size()) {
    size_t end = query.find('&', start);
    if (end == std::string::npos) end = query.size();
    const std::string item = query.substr(start, end - start);
    const size_t eq = item.find('=');
    const std::string key = item.substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : item.substr(eq + 1);
    if (key == "ttl") {
      u.ttl = parseInt(url, "ttl", value, 0, 255);
    } else if (key == "recv_buf_size") {
      u.recv_buf_size = parseInt(url, "recv_buf_size", value, 0, 1 << 30);
    } else if (!key.empty()) {
      throw std::invalid_argument("LCM URL '" + url + "': unknown option '" + key +
                                  "' (ttl, recv_buf_size)");
    }
    start = end + 1;
  }
}

void check(int rc, const char* what) {
  if (rc < 0)
    throw std::runtime_error(std::string("LCM receive socket: ") + what + ": " +
                             std::strerror(errno));
}

}  // namespace

bool isUdpmUrl(const std::string& url) { return effectiveLcmUrl(url).rfind("udpm://", 0) == 0; }

std::string effectiveLcmUrl(const std::string& url) {
  if (!url.empty()) return url;
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return env && *env ? env : kLiblcmDefaultUrl;
}

UdpmUrl parseUdpmUrl(const std::string& given) {
  const std::string url = effectiveLcmUrl(given);
  const std::string scheme = "udpm://";
  if (url.rfind(scheme, 0) != 0) {
    throw std::invalid_argument("LCM URL '" + url + "' is not udpm://GROUP:PORT?options");
  }
  UdpmUrl u;
  const size_t q = url.find('?', scheme.size());
  const std::string address =
      url.substr(scheme.size(), q == std::string::npos ? std::string::npos : q - scheme.size());
  if (q != std::string::npos) parseOptions(url, url.substr(q + 1), u);
  if (address.empty()) return u;
  const size_t colon = address.find(':');
  u.group = address.substr(0, colon);
  if (colon != std::string::npos) {
    u.port = static_cast<uint16_t>(parseInt(url, "port", address.substr(colon + 1), 1, 65535));
  }
  in_addr a{};
  if (inet_pton(AF_INET, u.group.c_str(), &a) != 1 || !IN_MULTICAST(ntohl(a.s_addr))) {
    throw std::invalid_argument("LCM URL '" + url + "': '" + u.group +
                                "' is not an IPv4 multicast group (224.0.0.0/4)");
  }
  return u;
}

ReceiverOptions securityOptions(const std::string& url,
                                const std::vector<std::string>& allow_senders,
                                const std::string& key_file) {
  ReceiverOptions o;
  for (const std::string& a : allow_senders) {
    in_addr addr{};
    if (inet_pton(AF_INET, a.c_str(), &addr) != 1) {
      throw std::invalid_argument("--allow-senders: '" + a + "' is not an IPv4 address");
    }
    o.allowed_senders.insert(ntohl(addr.s_addr));
  }
  if (!isUdpmUrl(url) && (!allow_senders.empty() || !key_file.empty())) {
    throw std::invalid_argument("--allow-senders and --key-file apply to udpm:// URLs, not '" +
                                url + "'");
  }
  if (!key_file.empty()) o.auth = MessageAuth::fromKeyFile(key_file);
  return o;
}

int64_t monotonicUs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1000000 + ts.tv_nsec / 1000;
}

// The socket liblcm 1.3.1 opens (lcm_udpm.c, _setup_recv_parts): SO_REUSEADDR and
// SO_REUSEPORT so that every process on the host binds the port, the group joined on the
// default interface, loopback on, a 2 MiB receive buffer unless the URL asks otherwise.
UdpmReceiver::UdpmReceiver(const std::string& url, ReceiverOptions options)
    : allowed_(std::move(options.allowed_senders)),
      auth_(std::move(options.auth)),
      reassembler_(options.limits),
      buffer_(kReceiveBufferBytes) {
  const UdpmUrl u = parseUdpmUrl(url);
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  try {
    check(fd_, "socket");
    const int one = 1;
    check(setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one), "SO_REUSEADDR");
    check(setsockopt(fd_, SOL_SOCKET, SO_REUSEPORT, &one, sizeof one), "SO_REUSEPORT");
    const unsigned char loop = 1;
    check(setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop), "IP_MULTICAST_LOOP");
    const int rcvbuf = u.recv_buf_size > 0 ? u.recv_buf_size : 2048 * 1024;
    setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);  // best effort, as liblcm
    // Bound to the group's address, not to every address (liblcm binds INADDR_ANY): a datagram
    // sent to this host's own address and the port (unicast, from anywhere it routes) is not
    // ours, and with IP_MULTICAST_ALL off neither is another group's traffic on the same port.
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    inet_pton(AF_INET, u.group.c_str(), &addr.sin_addr);
    addr.sin_port = htons(u.port);
    check(::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr), "bind");
    const int all = 0;
    setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_ALL, &all, sizeof all);  // Linux >= 2.6.31
    ip_mreq mreq{};
    mreq.imr_multiaddr = addr.sin_addr;
    mreq.imr_interface.s_addr = htonl(INADDR_ANY);
    check(setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq),
          "IP_ADD_MEMBERSHIP (is there a multicast route? see docs: ip route add 224.0.0.0/4)");
  } catch (...) {
    if (fd_ >= 0) ::close(fd_);
    throw;
  }
}

UdpmReceiver::~UdpmReceiver() {
  if (fd_ >= 0) ::close(fd_);
}

void UdpmReceiver::subscribe(const std::string& channel_regex, Handler handler) {
  subscriptions_.push_back({std::regex(channel_regex), std::move(handler)});
}

const ReceiverCounters& UdpmReceiver::counters() const {
  counters_.reassembly = reassembler_.counters();
  return counters_;
}

int UdpmReceiver::handleTimeout(int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  const int rc = ::poll(&p, 1, timeout_ms);
  if (rc < 0) return errno == EINTR ? 0 : -1;
  if (rc == 0) return 0;
  return readQueued();
}

// At most kMaxDatagramsPerCall per call, so that a flood cannot keep the caller (the
// worker, when it polls) from its other work.
int UdpmReceiver::readQueued() {
  constexpr int kMaxDatagramsPerCall = 512;
  int handled = 0;
  for (int i = 0; i < kMaxDatagramsPerCall; ++i) {
    sockaddr_in from{};
    socklen_t from_len = sizeof from;
    const ssize_t n = ::recvfrom(fd_, buffer_.data(), buffer_.size(), MSG_TRUNC,
                                 reinterpret_cast<sockaddr*>(&from), &from_len);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return handled;
      if (errno == EINTR) continue;
      return handled > 0 ? handled : -1;
    }
    ++counters_.datagrams;
    if (static_cast<size_t>(n) >= buffer_.size()) {
      ++counters_.truncated;
      continue;
    }
    const SenderId sender{ntohl(from.sin_addr.s_addr), ntohs(from.sin_port)};
    if (!allowed_.empty() && !allowed_.count(sender.address)) {
      ++counters_.not_allowed;
      continue;
    }
    std::optional<LcmMessage> m =
        reassembler_.feed(buffer_.data(), static_cast<size_t>(n), sender, monotonicUs());
    if (m) handled += dispatch(*m);
  }
  return handled;
}

// Hands a complete message to the handlers whose pattern matches its channel (with a key:
// only when its signature holds, and without the trailer). Returns 1 if anyone took it.
int UdpmReceiver::dispatch(const LcmMessage& m) {
  size_t size = m.data.size();
  if (auth_) {
    const std::optional<size_t> payload = auth_->verify(m.channel, m.data.data(), size);
    if (!payload) {
      ++counters_.not_signed;
      return 0;
    }
    size = *payload;
  }
  bool wanted = false;
  for (const Subscription& s : subscriptions_) {
    if (!std::regex_match(m.channel, s.pattern)) continue;
    wanted = true;
    s.handler(m.channel, m.data.data(), size);
  }
  if (!wanted) ++counters_.unsubscribed;
  return wanted ? 1 : 0;
}

}  // namespace sweepmap::net
