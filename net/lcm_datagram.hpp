// LCM's UDP multicast wire format (LCM's "UDP Multicast Protocol Description", the format of
// liblcm's lcm_udpm.c), read by code that trusts nothing it receives.
//
// A message is one datagram when channel + NUL + payload fits in 65499 bytes:
//   "LC02" (u32, big endian) | sequence number (u32) | channel, NUL | payload
// and fragments otherwise:
//   "LC03" | sequence number | message size (u32) | fragment offset (u32) |
//   fragment number (u16) | fragments in message (u16) | [fragment 0: channel, NUL] | data
//
// Debian 12's liblcm 1.3.1 checks a fragment with `offset + size > message size` in 32 bits,
// which wraps (offset 0xFFFFFFFF passes and the copy lands before the buffer), and trusts the
// channel's NUL. LcmReassembler checks every length and offset against the bytes present and
// the message size without overflow, bounds the channel, the message, the fragments and the
// memory held per sender and in all, and expires messages whose fragments stop coming.
// Everything refused is counted by reason; nothing it is fed can make it crash or grow.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace sweepmap::net {

constexpr uint32_t kLcmMagicShort = 0x4c433032;  // "LC02"
constexpr uint32_t kLcmMagicLong = 0x4c433033;   // "LC03"
constexpr size_t kLcmShortHeaderBytes = 8;
constexpr size_t kLcmLongHeaderBytes = 20;
// liblcm's own limits (lcm.h, udpm_util.h on Linux): what a conforming sender never exceeds.
constexpr size_t kLcmMaxChannelLength = 63;
constexpr size_t kLcmShortMessageMaxBytes = 65499;  // channel + NUL + payload in one datagram
constexpr size_t kLcmFragmentMaxPayload = 65487;    // bytes after the 20-byte header
constexpr size_t kLcmMaxMessageBytes = size_t{1} << 28;

// Bounds of what a receiver holds. The defaults fit every sweepmap message with a wide margin
// (the largest, a rig C sweep chunk, is under 64 KiB) and a Raspberry Pi's memory.
struct ReassemblyLimits {
  size_t max_message_bytes = 16u << 20;             // a fragmented message's declared size
  size_t max_pending_per_sender = 4;                // messages being reassembled, per sender
  size_t max_pending_bytes_per_sender = 24u << 20;  // bytes received and held, per sender
  size_t max_pending_bytes = 64u << 20;             // all senders together
  size_t max_senders = 64;                          // senders with messages being reassembled
  int64_t fragment_timeout_us = 1'000'000;          // since a message's last fragment
};

// Why a datagram or a pending message was refused. Stable names (refusalName) appear in the
// processes' status.
enum class Refusal : uint8_t {
  kTooShort,             // shorter than its header
  kBadMagic,             // neither LC02 nor LC03
  kChannelUnterminated,  // no NUL within the datagram
  kChannelTooLong,       // over 63 bytes, LCM's limit
  kChannelInvalid,       // empty, or a byte outside printable ASCII
  kMessageTooLarge,      // declared size over max_message_bytes
  kBadFragmentCount,     // 0 fragments, a fragment number past the count, or more
                         // fragments than the message has bytes
  kFragmentOutOfRange,   // offset + length past the declared size (checked in 64 bits)
  kFragmentMismatch,     // size or count differ from the message's earlier fragments
  kDuplicateFragment,    // a fragment number received twice
  kIncomplete,           // all fragments arrived but do not cover the message exactly
  kSenderLimit,          // over max_pending_per_sender / _bytes_per_sender / max_senders
  kMemoryLimit,          // an older pending message was evicted to stay within max_pending_bytes
  kTimedOut,             // a pending message's fragments stopped coming
  kCount
};
const char* refusalName(Refusal r);

// A complete, validated message.
struct LcmMessage {
  std::string channel;
  std::vector<uint8_t> data;
  uint32_t seqno = 0;
};

struct ReassemblyCounters {
  uint64_t datagrams = 0;  // fed
  uint64_t messages = 0;   // complete messages returned
  std::array<uint64_t, static_cast<size_t>(Refusal::kCount)> refused{};
  uint64_t refusedTotal() const;
  Refusal last_refusal = Refusal::kCount;  // kCount: none yet
};

// Identifies a datagram's sender (IPv4 address and UDP port: each publishing process has its
// own socket, so its own port).
struct SenderId {
  uint32_t address = 0;  // host byte order
  uint16_t port = 0;
  bool operator<(const SenderId& o) const {
    return address != o.address ? address < o.address : port < o.port;
  }
};

class LcmReassembler {
 public:
  explicit LcmReassembler(ReassemblyLimits limits = {});

  // Validates one datagram received from `sender` at `now_us` (any monotonic clock in
  // microseconds). Returns the message this datagram completes, if any. Expires pending
  // messages older than the timeout first.
  std::optional<LcmMessage> feed(const uint8_t* bytes, size_t size, SenderId sender,
                                 int64_t now_us);

  const ReassemblyCounters& counters() const { return counters_; }
  size_t pendingMessages() const;
  size_t pendingBytes() const { return pending_bytes_; }

 private:
  // A message being reassembled holds only the bytes that arrived (no buffer of the declared
  // size: a 40-byte datagram declaring 16 MiB costs 40 bytes, not a 16 MiB memset).
  struct Pending {
    std::string channel;  // from fragment 0; empty until it arrives
    uint32_t size = 0;    // declared message size
    uint16_t count = 0;   // declared fragments
    std::map<uint16_t, std::pair<uint32_t, std::vector<uint8_t>>> pieces;  // number -> offset, data
    size_t held = 0;  // bytes charged to the sender: data and bookkeeping
    int64_t last_us = 0;
    int64_t created_us = 0;
  };
  struct Sender {
    std::map<uint32_t, Pending> pending;  // by sequence number
    size_t bytes = 0;
  };
  struct LongHeader {
    uint32_t seqno, size, offset;
    uint16_t number, count;
  };

  std::optional<LcmMessage> feedShort(const uint8_t* bytes, size_t size);
  std::optional<LcmMessage> feedFragment(const uint8_t* bytes, size_t size, SenderId sender,
                                         int64_t now_us);
  std::optional<Refusal> checkFragment(const LongHeader& h, size_t data_bytes) const;
  Pending* pendingFor(const LongHeader& h, SenderId sender, int64_t now_us);
  void makeRoom(SenderId sender, size_t bytes);
  std::optional<LcmMessage> addFragment(Pending& p, const LongHeader& h, const uint8_t* data,
                                        size_t n, SenderId sender);
  static std::optional<std::vector<uint8_t>> join(const Pending& p);
  void erase(SenderId sender, uint32_t seqno);
  void expire(int64_t now_us);
  bool evictOldest(Refusal why, std::optional<std::pair<SenderId, uint32_t>> keep = {});
  std::nullopt_t refuse(Refusal r);

  ReassemblyLimits limits_;
  ReassemblyCounters counters_;
  std::map<SenderId, Sender> senders_;
  size_t pending_bytes_ = 0;
};

// Validates a channel name as sweepmap accepts it: 1..63 bytes of printable ASCII.
std::optional<Refusal> checkChannel(const uint8_t* begin, size_t max_bytes, size_t* length);

// The datagrams liblcm 1.3.1 would send for this message (same sizes, fragment boundaries and
// headers), so that lcm-spy, lcm-logger and liblcm receivers read what we publish.
std::vector<std::vector<uint8_t>> encodeLcmDatagrams(const std::string& channel,
                                                     const uint8_t* data, size_t size,
                                                     uint32_t seqno);

}  // namespace sweepmap::net
