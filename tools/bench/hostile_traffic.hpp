// What an intruder on the robot's network sends (issue 21), for the two-host intruder test and
// the flood benchmark: datagrams that crash liblcm 1.3.1 receivers, malformed datagrams,
// well-formed LCM datagrams carrying messages that break decoders, and forged messages
// (another run's traffic: unsigned, or signed with a key the robot does not hold). Everything
// is made deterministically from a seed; nothing here is sent anywhere but where a
// MulticastSender is told.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "net/message_auth.hpp"

namespace sweepmap::hostile {

using Bytes = std::vector<uint8_t>;

// ---- Datagrams that are not valid LCM ---------------------------------------------------

// Fragment 0 of an LC03 message on `channel`, offset 0xFFFFFFFF, 131 bytes: liblcm 1.3.1's
// 32-bit check `offset + size > message size` wraps, and its copy lands before the buffer.
Bytes offsetWrap(const std::string& channel, uint32_t seqno);
// An LC02 whose channel has no NUL inside the datagram (liblcm reports a data size of -1).
Bytes unterminatedChannel(const std::string& channel, uint32_t seqno);
// Fragment 0 of a 100 kB message that never completes (it costs the receiver memory until
// it expires).
Bytes openFragment(const std::string& channel, uint32_t seqno);
// The above on each of `channels`, then `mutated` copies with random header bytes (seeded).
std::vector<Bytes> malformedDatagrams(const std::vector<std::string>& channels, int mutated,
                                      uint32_t seed);

// ---- Well-formed datagrams with messages that break decoders ----------------------------

// A map_save_t whose path length is INT32_MIN (22 bytes: lcm-gen's `len - 1` overflows).
Bytes mapSaveWithMinLength();
// A process_status_t claiming `count` counters with none present (2^26 took a trusting
// decoder to 2.2 GB, 2^31-1 killed it).
Bytes statusWithHugeCount(const std::string& process, uint32_t count = 1u << 26);
// A process_status_t whose process name's length is INT32_MIN.
Bytes statusWithMinLength();
// A sweep_status_t whose reason's length is INT32_MIN.
Bytes sweepStatusWithMinLength();
// A process_status_t whose detail is not UTF-8.
Bytes statusWithBadUtf8(const std::string& process);
// A map_save_t asking the mapper to save `path`.
Bytes mapSave(const std::string& path, int64_t utime);

// ---- Forged messages --------------------------------------------------------------------

// A message to publish, as lcm_publish would: the channel and the payload.
struct Forged {
  std::string channel;
  Bytes payload;
};
// Every event of an LCM log on a channel of `channels` (all if empty), in log order.
std::vector<Forged> messagesOfLog(const std::string& log, const std::vector<std::string>& channels);
// The decoder-breaking messages above on their channels (MAP_SAVE, STATUS_*).
std::vector<Forged> decoderBreakers();
// `m` signed with a key the robot does not hold (net/message_auth.hpp's trailer).
Forged wronglySigned(const Forged& m, uint8_t key_byte = 0x5a);

// The datagrams liblcm would send for `messages`, sequence numbers from `first_seqno`.
std::vector<Bytes> datagramsOf(const std::vector<Forged>& messages, uint32_t first_seqno);

// ---- Sending ----------------------------------------------------------------------------

// A UDP socket sending to an LCM multicast group (ttl 1, looped back to this host), as any
// process on the link could. Create it inside the network namespace it must send from.
class MulticastSender {
 public:
  // Throws std::runtime_error naming the call that failed.
  MulticastSender(const std::string& group, uint16_t port);
  ~MulticastSender();
  MulticastSender(const MulticastSender&) = delete;
  MulticastSender& operator=(const MulticastSender&) = delete;
  // Sends every datagram, pausing `pause_us` after each `burst` of them (a flood, not a
  // socket-buffer overflow test). Returns how many the kernel took.
  size_t send(const std::vector<Bytes>& datagrams, int burst = 100, int pause_us = 2000);

 private:
  int fd_ = -1;
  std::array<uint8_t, 16> to_{};  // sockaddr_in
};

}  // namespace sweepmap::hostile
