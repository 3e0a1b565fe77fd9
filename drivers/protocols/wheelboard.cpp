#include "drivers/protocols/wheelboard.hpp"

#include <algorithm>
#include <cmath>

namespace sweepmap {
namespace wheelboard {
namespace {

constexpr size_t kHeader = 6, kCrc = 2, kMaxPayload = 64;

uint16_t u16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t u32(const uint8_t* p) {
  return uint32_t{p[0]} | (uint32_t{p[1]} << 8) | (uint32_t{p[2]} << 16) | (uint32_t{p[3]} << 24);
}
void put16(std::string* s, uint16_t v) {
  s->push_back(static_cast<char>(v & 0xff));
  s->push_back(static_cast<char>(v >> 8));
}
void put32(std::string* s, uint32_t v) {
  for (int i = 0; i < 4; ++i) s->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

std::string frame(uint8_t type, uint16_t seq, const std::string& payload) {
  std::string s = "\xA5\x5B";
  s.push_back(static_cast<char>(type));
  s.push_back(static_cast<char>(payload.size()));
  put16(&s, seq);
  s += payload;
  put16(&s, crc16(reinterpret_cast<const uint8_t*>(s.data()) + 2, s.size() - 2));
  return s;
}

}  // namespace

uint16_t crc16(const uint8_t* data, size_t size) {
  uint32_t c = 0xFFFF;
  for (size_t j = 0; j < size; ++j) {
    c ^= uint32_t{data[j]} << 8;
    for (int i = 0; i < 8; ++i) c = (c & 0x8000) ? ((c << 1) ^ 0x1021) : (c << 1);
  }
  return static_cast<uint16_t>(c);
}

void Decoder::reset() { *this = Decoder(); }

void Decoder::feed(const uint8_t* data, size_t size, std::vector<Event>* out) {
  buffer_.feed(data, size, &counters_, out, [&](const uint8_t* p, size_t left, int64_t offset) {
    return parseFrame(p, left, offset, out);
  });
}

void Decoder::finish(std::vector<Event>* out) {
  buffer_.finish(&counters_, out, [&](const uint8_t* p, size_t left, int64_t offset) {
    return parseFrame(p, left, offset, out);
  });
}

// A5 5B, type, length, sequence number, payload, CRC.
ParseStep Decoder::parseFrame(const uint8_t* p, size_t left, int64_t offset,
                              std::vector<Event>* out) {
  if (const auto not_yet = expectHeader(p, left, 0xA5, 0x5B, kHeader)) return *not_yet;
  const uint8_t type = p[2];
  const size_t n = p[3];
  const bool known = (type == kTypeTicks && n == 14) || (type == kTypeSpeed && n == 4);
  if (!known && (type == 0 || type > 0x0F || n > kMaxPayload)) {
    return ParseStep::skip();  // not a header
  }
  if (left < kHeader + n + kCrc) return ParseStep::wait();
  if (crc16(p + 2, kHeader - 2 + n) != u16(p + kHeader + n)) {
    return buffer_.dropBadPacket(
        offset,
        "wheel board frame (type " + std::to_string(type) + "): CRC mismatch; frame dropped",
        &counters_, out);
  }
  buffer_.flushSkipped(&counters_, out);
  decodeFrame(p, offset, out);
  return ParseStep::take(kHeader + n + kCrc);
}

// A frame whose CRC holds: its sequence number checked for gaps, its payload decoded.
void Decoder::decodeFrame(const uint8_t* p, int64_t offset, std::vector<Event>* out) {
  const uint8_t type = p[2];
  const size_t n = p[3];
  const uint16_t seq = u16(p + 4);
  const uint8_t* d = p + kHeader;
  const size_t slot = std::min<size_t>(type, 2);
  if (have_seq_[slot]) gaps_ += static_cast<uint16_t>(seq - last_seq_[slot] - 1);
  have_seq_[slot] = true;
  last_seq_[slot] = seq;
  ++counters_.packets;
  if (type == kTypeTicks && n == 14) {
    Ticks t;
    t.seq = seq;
    t.time_us = u32(d);
    t.left = static_cast<int32_t>(u32(d + 4));
    t.right = static_cast<int32_t>(u32(d + 8));
    t.flags = u16(d + 12);
    t.offset = offset;
    if (t.flags & (kFlagLeftEncoder | kFlagRightEncoder | kFlagDriver)) ++counters_.device_errors;
    out->push_back(t);
  } else if (type == kTypeSpeed && n == 4) {
    Speed s;
    s.seq = seq;
    s.v_m_s = static_cast<int16_t>(u16(d)) * 1e-3;
    s.w_rad_s = static_cast<int16_t>(u16(d + 2)) * 1e-3;
    s.offset = offset;
    out->push_back(s);
  } else {
    ++counters_.device_errors;
    out->push_back(DecodeError{offset, "wheel board: frame type " + std::to_string(type) +
                                           " with " + std::to_string(n) +
                                           " bytes is not one this host knows; skipped"});
  }
}

std::string encodeTicks(const Ticks& t) {
  std::string p;
  put32(&p, t.time_us);
  put32(&p, static_cast<uint32_t>(t.left));
  put32(&p, static_cast<uint32_t>(t.right));
  put16(&p, t.flags);
  return frame(kTypeTicks, t.seq, p);
}

std::string encodeSpeed(uint16_t seq, double v_m_s, double w_rad_s) {
  const auto q = [](double x) {
    return static_cast<uint16_t>(
        static_cast<int16_t>(std::clamp(std::lround(x * 1e3), -32768L, 32767L)));
  };
  std::string p;
  put16(&p, q(v_m_s));
  put16(&p, q(w_rad_s));
  return frame(kTypeSpeed, seq, p);
}

}  // namespace wheelboard
}  // namespace sweepmap
