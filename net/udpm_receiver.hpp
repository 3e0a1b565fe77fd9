// Receives LCM traffic from a UDP multicast group (an `udpm://` provider URL) through
// LcmReassembler, so that no datagram reaches liblcm 1.3.1's receive code. Publishing may stay
// with liblcm: its send path parses nothing from the network, and liblcm opens its receive
// socket only when something subscribes through it or asks for its file descriptor.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "net/lcm_datagram.hpp"
#include "net/message_auth.hpp"

namespace sweepmap::net {

// An `udpm://GROUP:PORT?ttl=N&recv_buf_size=N` URL as liblcm reads it (both keys optional;
// GROUP defaults to 239.255.76.67 and PORT to 7667 when the URL is just "udpm://").
struct UdpmUrl {
  std::string group = "239.255.76.67";
  uint16_t port = 7667;
  int ttl = 0;
  int recv_buf_size = 0;  // bytes; 0: liblcm's 2 MiB request
};
// Throws std::invalid_argument naming the URL and the part that is wrong.
UdpmUrl parseUdpmUrl(const std::string& url);
// The provider URL that an empty one means (LCM_DEFAULT_URL, else liblcm's default).
std::string effectiveLcmUrl(const std::string& url);
bool isUdpmUrl(const std::string& url);

struct ReceiverCounters {
  uint64_t datagrams = 0;     // read from the socket
  uint64_t truncated = 0;     // larger than any LCM datagram can be
  uint64_t not_allowed = 0;   // from an address outside the allow-list
  uint64_t unsubscribed = 0;  // complete messages on channels nobody here wants
  uint64_t not_signed = 0;    // with a key: unsigned or wrongly signed messages
  ReassemblyCounters reassembly;
};

// Who may be heard. Both empty: everyone (a bench); the generated systemd units set both.
struct ReceiverOptions {
  std::set<uint32_t> allowed_senders;  // IPv4 addresses, host byte order; empty: any
  std::optional<MessageAuth> auth;     // set: only messages signed with this key pass
  ReassemblyLimits limits;
};

// --allow-senders (IPv4 addresses) and --key-file as every command takes them, for `url`.
// Throws std::invalid_argument naming the option and what is wrong.
ReceiverOptions securityOptions(const std::string& url,
                                const std::vector<std::string>& allow_senders,
                                const std::string& key_file);

class UdpmReceiver {
 public:
  using Handler = std::function<void(const std::string& channel, const uint8_t* data, size_t size)>;

  // Joins the group of `url` (see parseUdpmUrl). Throws std::invalid_argument for a bad URL,
  // std::runtime_error on a socket error (naming the call).
  explicit UdpmReceiver(const std::string& url, ReceiverOptions options = {});
  ~UdpmReceiver();
  UdpmReceiver(const UdpmReceiver&) = delete;
  UdpmReceiver& operator=(const UdpmReceiver&) = delete;

  // Messages on channels that match `channel_regex` in full (LCM's subscription syntax) go to
  // `handler`. Call before handleTimeout; not thread-safe against it.
  void subscribe(const std::string& channel_regex, Handler handler);

  // Waits up to timeout_ms for datagrams, then reads every datagram queued on the socket and
  // hands each complete, valid message to its handlers. Returns the number of messages handed
  // over, 0 on a timeout, -1 on a socket error (errno set; EINTR is not an error: 0).
  int handleTimeout(int timeout_ms);

  int fileno() const { return fd_; }
  const ReceiverCounters& counters() const;

 private:
  int readQueued();
  int dispatch(const LcmMessage& m);

  int fd_ = -1;
  std::set<uint32_t> allowed_;
  std::optional<MessageAuth> auth_;
  LcmReassembler reassembler_;
  struct Subscription {
    std::regex pattern;
    Handler handler;
  };
  std::vector<Subscription> subscriptions_;
  mutable ReceiverCounters counters_;
  std::vector<uint8_t> buffer_;
};

// Monotonic microseconds (CLOCK_MONOTONIC): the reassembler's clock.
int64_t monotonicUs();

}  // namespace sweepmap::net
