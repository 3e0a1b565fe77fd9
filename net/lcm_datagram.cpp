#include "net/lcm_datagram.hpp"

#include <algorithm>
#include <cstring>

namespace sweepmap::net {
namespace {

uint32_t readU32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3];
}
uint16_t readU16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }
void putU32(std::vector<uint8_t>& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<uint8_t>(v >> shift));
}
void putU16(std::vector<uint8_t>& out, uint16_t v) {
  out.push_back(static_cast<uint8_t>(v >> 8));
  out.push_back(static_cast<uint8_t>(v));
}

}  // namespace

const char* refusalName(Refusal r) {
  switch (r) {
    case Refusal::kTooShort:
      return "too_short";
    case Refusal::kBadMagic:
      return "bad_magic";
    case Refusal::kChannelUnterminated:
      return "channel_unterminated";
    case Refusal::kChannelTooLong:
      return "channel_too_long";
    case Refusal::kChannelInvalid:
      return "channel_invalid";
    case Refusal::kMessageTooLarge:
      return "message_too_large";
    case Refusal::kBadFragmentCount:
      return "bad_fragment_count";
    case Refusal::kFragmentOutOfRange:
      return "fragment_out_of_range";
    case Refusal::kFragmentMismatch:
      return "fragment_mismatch";
    case Refusal::kDuplicateFragment:
      return "duplicate_fragment";
    case Refusal::kIncomplete:
      return "incomplete";
    case Refusal::kSenderLimit:
      return "sender_limit";
    case Refusal::kMemoryLimit:
      return "memory_limit";
    case Refusal::kTimedOut:
      return "timed_out";
    case Refusal::kCount:
      break;
  }
  return "none";
}

uint64_t ReassemblyCounters::refusedTotal() const {
  uint64_t total = 0;
  for (uint64_t n : refused) total += n;
  return total;
}

std::optional<Refusal> checkChannel(const uint8_t* begin, size_t max_bytes, size_t* length) {
  const size_t scan = std::min(max_bytes, kLcmMaxChannelLength + 1);
  const auto* nul = static_cast<const uint8_t*>(std::memchr(begin, 0, scan));
  if (!nul) {
    return max_bytes > kLcmMaxChannelLength ? Refusal::kChannelTooLong
                                            : Refusal::kChannelUnterminated;
  }
  *length = static_cast<size_t>(nul - begin);
  if (*length == 0) return Refusal::kChannelInvalid;
  for (const uint8_t* c = begin; c != nul; ++c) {
    if (*c < 0x20 || *c > 0x7e) return Refusal::kChannelInvalid;
  }
  return std::nullopt;
}

LcmReassembler::LcmReassembler(ReassemblyLimits limits) : limits_(limits) {}

std::nullopt_t LcmReassembler::refuse(Refusal r) {
  ++counters_.refused[static_cast<size_t>(r)];
  counters_.last_refusal = r;
  return std::nullopt;
}

size_t LcmReassembler::pendingMessages() const {
  size_t n = 0;
  for (const auto& [id, s] : senders_) n += s.pending.size();
  return n;
}

std::optional<LcmMessage> LcmReassembler::feed(const uint8_t* bytes, size_t size, SenderId sender,
                                               int64_t now_us) {
  ++counters_.datagrams;
  expire(now_us);
  if (size < 4) return refuse(Refusal::kTooShort);
  const uint32_t magic = readU32(bytes);
  if (magic == kLcmMagicShort) return feedShort(bytes, size);
  if (magic == kLcmMagicLong) return feedFragment(bytes, size, sender, now_us);
  return refuse(Refusal::kBadMagic);
}

std::optional<LcmMessage> LcmReassembler::feedShort(const uint8_t* bytes, size_t size) {
  if (size < kLcmShortHeaderBytes + 2) return refuse(Refusal::kTooShort);  // channel + NUL
  size_t channel_length = 0;
  const uint8_t* channel = bytes + kLcmShortHeaderBytes;
  if (auto r = checkChannel(channel, size - kLcmShortHeaderBytes, &channel_length)) {
    return refuse(*r);
  }
  LcmMessage m;
  m.seqno = readU32(bytes + 4);
  m.channel.assign(reinterpret_cast<const char*>(channel), channel_length);
  m.data.assign(channel + channel_length + 1, bytes + size);
  ++counters_.messages;
  return m;
}

std::optional<Refusal> LcmReassembler::checkFragment(const LongHeader& h, size_t data_bytes) const {
  if (h.size > limits_.max_message_bytes || h.size > kLcmMaxMessageBytes) {
    return Refusal::kMessageTooLarge;
  }
  // Every fragment but possibly the first carries at least one byte of the message.
  if (h.count == 0 || h.number >= h.count || uint64_t{h.count} > uint64_t{h.size} + 1) {
    return Refusal::kBadFragmentCount;
  }
  if (uint64_t{h.offset} + data_bytes > h.size) return Refusal::kFragmentOutOfRange;
  return std::nullopt;
}

std::optional<LcmMessage> LcmReassembler::feedFragment(const uint8_t* bytes, size_t size,
                                                       SenderId sender, int64_t now_us) {
  if (size < kLcmLongHeaderBytes) return refuse(Refusal::kTooShort);
  const LongHeader h{readU32(bytes + 4), readU32(bytes + 8), readU32(bytes + 12),
                     readU16(bytes + 16), readU16(bytes + 18)};
  const uint8_t* data = bytes + kLcmLongHeaderBytes;
  size_t n = size - kLcmLongHeaderBytes;
  std::string channel;
  if (h.number == 0) {
    size_t channel_length = 0;
    if (n == 0) return refuse(Refusal::kChannelUnterminated);
    if (auto r = checkChannel(data, n, &channel_length)) return refuse(*r);
    channel.assign(reinterpret_cast<const char*>(data), channel_length);
    data += channel_length + 1;
    n -= channel_length + 1;
  }
  if (auto r = checkFragment(h, n)) return refuse(*r);
  Pending* p = pendingFor(h, sender, now_us);
  if (!p) return std::nullopt;  // refused and counted by pendingFor
  p->last_us = now_us;
  if (h.number == 0) p->channel = std::move(channel);
  return addFragment(*p, h, data, n, sender);
}

// The message this fragment belongs to: an existing one of the same sender and sequence
// number (whose size and count must agree), or a new one within the sender's and the
// receiver's bounds. Fragments may come in any order: every fragment names the size.
LcmReassembler::Pending* LcmReassembler::pendingFor(const LongHeader& h, SenderId sender,
                                                    int64_t now_us) {
  auto s = senders_.find(sender);
  if (s != senders_.end()) {
    auto it = s->second.pending.find(h.seqno);
    if (it != s->second.pending.end()) {
      if (it->second.size != h.size || it->second.count != h.count) {
        refuse(Refusal::kFragmentMismatch);
        erase(sender, h.seqno);
        return nullptr;
      }
      return &it->second;
    }
  } else {
    // A full table gives way oldest first: a real sender's fragments come back to back, so
    // its message completes long before a flood's stale ones are the oldest.
    while (senders_.size() >= limits_.max_senders && evictOldest(Refusal::kSenderLimit)) {
    }
  }
  makeRoom(sender, kLcmFragmentMaxPayload);
  Pending& p = senders_[sender].pending[h.seqno];
  p.size = h.size;
  p.count = h.count;
  p.created_us = now_us;
  p.last_us = now_us;
  return &p;
}

// A sender publishes one message at a time (liblcm holds its transmit lock across a message's
// fragments): its own oldest unfinished messages give way first, then the oldest of all.
void LcmReassembler::makeRoom(SenderId sender, size_t bytes) {
  for (auto s = senders_.find(sender); s != senders_.end(); s = senders_.find(sender)) {
    const Sender& owner = s->second;
    if (owner.pending.size() < limits_.max_pending_per_sender &&
        owner.bytes + bytes <= limits_.max_pending_bytes_per_sender) {
      break;
    }
    refuse(Refusal::kSenderLimit);
    erase(sender, owner.pending.begin()->first);
  }
  while (pending_bytes_ + bytes > limits_.max_pending_bytes && evictOldest(Refusal::kMemoryLimit)) {
  }
}

std::optional<LcmMessage> LcmReassembler::addFragment(Pending& p, const LongHeader& h,
                                                      const uint8_t* data, size_t n,
                                                      SenderId sender) {
  if (p.pieces.count(h.number)) return refuse(Refusal::kDuplicateFragment);
  constexpr size_t kPieceOverhead = 64;  // a map node and a vector header, roughly
  const size_t charge = n + kPieceOverhead;
  if (senders_[sender].bytes + charge > limits_.max_pending_bytes_per_sender) {
    erase(sender, h.seqno);
    return refuse(Refusal::kSenderLimit);
  }
  while (pending_bytes_ + charge > limits_.max_pending_bytes) {
    if (!evictOldest(Refusal::kMemoryLimit, std::make_pair(sender, h.seqno))) {
      erase(sender, h.seqno);
      return refuse(Refusal::kMemoryLimit);
    }
  }
  Sender& owner = senders_[sender];
  p.pieces.emplace(h.number, std::make_pair(h.offset, std::vector<uint8_t>(data, data + n)));
  p.held += charge;
  owner.bytes += charge;
  pending_bytes_ += charge;
  if (p.pieces.size() < p.count) return std::nullopt;
  std::optional<std::vector<uint8_t>> joined = join(p);
  std::string channel = std::move(p.channel);
  erase(sender, h.seqno);
  if (!joined || channel.empty()) return refuse(Refusal::kIncomplete);
  ++counters_.messages;
  return LcmMessage{std::move(channel), std::move(*joined), h.seqno};
}

// The message, when its fragments tile it exactly: in offset order, each starting where the
// previous one ended, the last ending at the declared size.
std::optional<std::vector<uint8_t>> LcmReassembler::join(const Pending& p) {
  std::vector<const std::pair<uint32_t, std::vector<uint8_t>>*> order;
  order.reserve(p.pieces.size());
  for (const auto& [number, piece] : p.pieces) order.push_back(&piece);
  std::stable_sort(order.begin(), order.end(),
                   [](const auto* a, const auto* b) { return a->first < b->first; });
  std::vector<uint8_t> data;
  data.reserve(p.size);
  for (const auto* piece : order) {
    if (piece->first != data.size()) return std::nullopt;
    data.insert(data.end(), piece->second.begin(), piece->second.end());
  }
  if (data.size() != p.size) return std::nullopt;
  return data;
}

void LcmReassembler::erase(SenderId sender, uint32_t seqno) {
  auto s = senders_.find(sender);
  if (s == senders_.end()) return;
  auto it = s->second.pending.find(seqno);
  if (it != s->second.pending.end()) {
    s->second.bytes -= it->second.held;
    pending_bytes_ -= it->second.held;
    s->second.pending.erase(it);
  }
  if (s->second.pending.empty()) senders_.erase(s);
}

void LcmReassembler::expire(int64_t now_us) {
  std::vector<std::pair<SenderId, uint32_t>> stale;
  for (const auto& [id, s] : senders_) {
    for (const auto& [seqno, p] : s.pending) {
      // A clock that went back (now before creation) starts afresh too.
      if (now_us - p.last_us > limits_.fragment_timeout_us || now_us < p.created_us) {
        stale.emplace_back(id, seqno);
      }
    }
  }
  for (const auto& [id, seqno] : stale) {
    refuse(Refusal::kTimedOut);
    erase(id, seqno);
  }
}

bool LcmReassembler::evictOldest(Refusal why, std::optional<std::pair<SenderId, uint32_t>> keep) {
  const SenderId* oldest_sender = nullptr;
  uint32_t oldest_seqno = 0;
  int64_t oldest_us = 0;
  for (const auto& [id, s] : senders_) {
    for (const auto& [seqno, p] : s.pending) {
      const bool kept = keep && !(id < keep->first) && !(keep->first < id) && seqno == keep->second;
      if (!kept && (!oldest_sender || p.last_us < oldest_us)) {
        oldest_sender = &id;
        oldest_seqno = seqno;
        oldest_us = p.last_us;
      }
    }
  }
  if (!oldest_sender) return false;
  refuse(why);
  erase(*oldest_sender, oldest_seqno);
  return true;
}

std::vector<std::vector<uint8_t>> encodeLcmDatagrams(const std::string& channel,
                                                     const uint8_t* data, size_t size,
                                                     uint32_t seqno) {
  std::vector<std::vector<uint8_t>> out;
  const size_t payload = channel.size() + 1 + size;
  if (payload <= kLcmShortMessageMaxBytes) {
    std::vector<uint8_t>& d = out.emplace_back();
    d.reserve(kLcmShortHeaderBytes + payload);
    putU32(d, kLcmMagicShort);
    putU32(d, seqno);
    d.insert(d.end(), channel.begin(), channel.end());
    d.push_back(0);
    d.insert(d.end(), data, data + size);
    return out;
  }
  const size_t count = (payload + kLcmFragmentMaxPayload - 1) / kLcmFragmentMaxPayload;
  size_t offset = 0;
  for (size_t number = 0; number < count; ++number) {
    const size_t room =
        number == 0 ? kLcmFragmentMaxPayload - (channel.size() + 1) : kLcmFragmentMaxPayload;
    const size_t n = std::min(room, size - offset);
    std::vector<uint8_t>& d = out.emplace_back();
    d.reserve(kLcmLongHeaderBytes + channel.size() + 1 + n);
    putU32(d, kLcmMagicLong);
    putU32(d, seqno);
    putU32(d, static_cast<uint32_t>(size));
    putU32(d, static_cast<uint32_t>(offset));
    putU16(d, static_cast<uint16_t>(number));
    putU16(d, static_cast<uint16_t>(count));
    if (number == 0) {
      d.insert(d.end(), channel.begin(), channel.end());
      d.push_back(0);
    }
    d.insert(d.end(), data + offset, data + offset + n);
    offset += n;
  }
  return out;
}

}  // namespace sweepmap::net
