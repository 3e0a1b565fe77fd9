#include "drivers/protocols/ydlidar.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "drivers/protocols/descriptor.hpp"

namespace sweepmap {
namespace ydlidar {
namespace {

constexpr size_t kHeader = 10;     // PH CT LSN FSA LSA CS
constexpr size_t kDescriptor = 7;  // A5 5A len(4) type

uint16_t le16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
void put16(std::string* s, uint16_t v) {
  s->push_back(static_cast<char>(v & 0xff));
  s->push_back(static_cast<char>(v >> 8));
}

uint16_t encodeAngle(double deg) {
  double d = std::fmod(deg, 360.0);
  if (d < 0) d += 360.0;
  auto q = static_cast<int>(std::lround(d * 64.0));
  if (q >= 360 * 64) q -= 360 * 64;
  return static_cast<uint16_t>((q << 1) | 1);
}

struct PacketHeader {
  uint8_t ct = 0;
  size_t lsn = 0;
  uint16_t fsa = 0, lsa = 0, cs = 0;
};

PacketHeader readHeader(const uint8_t* p) {
  return PacketHeader{p[2], p[3], le16(p + 4), le16(p + 6), le16(p + 8)};
}

// The XOR of the packet's 16-bit words but its check code.
uint16_t checkCode(const uint8_t* p, const PacketHeader& h) {
  uint16_t x = le16(p) ^ h.fsa ^ static_cast<uint16_t>(h.ct | (h.lsn << 8)) ^ h.lsa;
  for (size_t i = 0; i < h.lsn; ++i) x ^= le16(p + kHeader + 2 * i);
  return x;
}

DeviceInfo decodeInfo(const uint8_t* c, int64_t offset) {
  DeviceInfo info;
  info.model = c[0];
  info.firmware_major = c[1];  // the manual: low byte major, high byte minor
  info.firmware_minor = c[2];
  info.hardware = c[3];
  info.serial = hexBytes(c + 4, 16);
  info.offset = offset;
  return info;
}

Health decodeHealth(const uint8_t* c, int64_t offset) {
  Health h;
  h.status = c[0];
  h.error_code = le16(c + 1);
  h.offset = offset;
  return h;
}

}  // namespace

// The first-level angle step between a packet's samples [deg], as the vendor SDK computes it
// (YDLIDAR/YDLidar-SDK src/YDlidarDriver.cpp, commit d37ace902f73, waitPackage, case 7): a
// packet of one sample has none; LSA below FSA is the 360 -> 0 wrap only when FSA > 270 deg
// and LSA < 90 deg, else the packet's angles are not trusted and the previous packet's step
// is kept (a real X4 sends such packets: tests/data/real/README.md).
double Decoder::sampleStep(size_t lsn, uint16_t fsa, uint16_t lsa) {
  if (lsn <= 1) return 0.0;
  const int first = fsa >> 1, last = lsa >> 1;  // 1/64 deg
  if (last < first && !(first > 270 * 64 && last < 90 * 64)) {
    ++counters_.anomalies;
    return last_step_deg_;
  }
  const int span = last >= first ? last - first : 360 * 64 + last - first;
  last_step_deg_ = span / 64.0 / static_cast<double>(lsn - 1);
  return last_step_deg_;
}

namespace {

// The samples' distances and angles: first-level from FSA by `step_deg`, then corrected.
Packet decodePacket(const uint8_t* p, const PacketHeader& h, double step_deg, int64_t offset) {
  Packet packet;
  packet.ring_start = h.ct & 1;
  packet.offset = offset;
  packet.end_offset = offset + static_cast<int64_t>(kHeader + 2 * h.lsn);
  const double first = (h.fsa >> 1) / 64.0;
  for (size_t i = 0; i < h.lsn; ++i) {
    Sample s;
    s.distance_mm = le16(p + kHeader + 2 * i) / 4.0;
    s.raw_angle_deg = first + step_deg * static_cast<double>(i);
    double a = s.raw_angle_deg + angleCorrectionDeg(s.distance_mm);
    a = std::fmod(a, 360.0);
    if (a < 0) a += 360.0;
    s.raw_angle_deg = std::fmod(s.raw_angle_deg, 360.0);
    s.angle_deg = a;
    packet.samples.push_back(s);
  }
  return packet;
}

}  // namespace

double angleCorrectionDeg(double d) {
  if (d <= 0.0) return 0.0;
  return std::atan(21.8 * (155.3 - d) / (155.3 * d)) * 180.0 / M_PI;
}

void Decoder::reset() {
  counters_ = {};
  buffer_.clear();
  last_step_deg_ = 0.0;
}

ParseStep Decoder::parse(const uint8_t* p, size_t left, int64_t offset, std::vector<Event>* out) {
  if (p[0] == 0xA5) return parseReply(p, left, offset, out);
  if (p[0] == 0xAA) return parsePacket(p, left, offset, out);
  return ParseStep::skip();
}

void Decoder::feed(const uint8_t* data, size_t size, std::vector<Event>* out) {
  // Buffered: at most one packet header's worth is waited for, a packet is at most
  // 10 + 2 * 255 bytes.
  buffer_.feed(data, size, &counters_, out, [&](const uint8_t* p, size_t left, int64_t offset) {
    return parse(p, left, offset, out);
  });
}

void Decoder::finish(std::vector<Event>* out) {
  buffer_.finish(&counters_, out, [&](const uint8_t* p, size_t left, int64_t offset) {
    return parse(p, left, offset, out);
  });
}

// A5 5A: a reply descriptor (the scan stream's start, device info or health).
ParseStep Decoder::parseReply(const uint8_t* p, size_t left, int64_t offset,
                              std::vector<Event>* out) {
  if (const auto not_yet = expectHeader(p, left, 0xA5, 0x5A, kDescriptor)) return *not_yet;
  Descriptor d;
  parseDescriptor(p, &d);
  if (d.type == kTypeScan && d.mode == 1) {
    buffer_.flushSkipped(&counters_, out);
    ++counters_.packets;
    out->push_back(ScanStart{offset});
    return ParseStep::take(kDescriptor);
  }
  const bool info = d.type == kTypeInfo && d.length == 20 && d.mode == 0;
  const bool health = d.type == kTypeHealth && d.length == 3 && d.mode == 0;
  if (!info && !health) return ParseStep::skip();  // a descriptor we do not know: a false start
  if (left < kDescriptor + d.length) return ParseStep::wait();
  buffer_.flushSkipped(&counters_, out);
  ++counters_.packets;
  const uint8_t* c = p + kDescriptor;
  if (info) {
    out->push_back(decodeInfo(c, offset));
  } else {
    const Health h = decodeHealth(c, offset);
    if (h.status != 0) ++counters_.device_errors;
    out->push_back(h);
  }
  return ParseStep::take(kDescriptor + d.length);
}

// AA 55: a sample packet, checked against its check code.
ParseStep Decoder::parsePacket(const uint8_t* p, size_t left, int64_t offset,
                               std::vector<Event>* out) {
  if (const auto not_yet = expectHeader(p, left, 0xAA, 0x55, kHeader)) return *not_yet;
  const PacketHeader h = readHeader(p);
  if (h.lsn == 0 || (h.fsa & 1) == 0 || (h.lsa & 1) == 0 || ((h.ct & 1) && h.lsn != 1)) {
    return ParseStep::skip();  // not a packet header: resynchronise at the next byte
  }
  const size_t total = kHeader + 2 * h.lsn;
  if (left < total) return ParseStep::wait();
  if (checkCode(p, h) != h.cs) {
    return buffer_.dropBadPacket(
        offset,
        "YDLIDAR packet (LSN " + std::to_string(h.lsn) + "): check code mismatch; packet dropped",
        &counters_, out);
  }
  buffer_.flushSkipped(&counters_, out);
  ++counters_.packets;
  out->push_back(decodePacket(p, h, sampleStep(h.lsn, h.fsa, h.lsa), offset));
  return ParseStep::take(total);
}

std::string encodeDescriptor(uint32_t length, int mode, uint8_t type) {
  return sweepmap::encodeDescriptor(length, mode, type);
}

std::string encodeInfo(int model, int fw_major, int fw_minor, int hardware,
                       const std::string& serial16) {
  return encodeInfoReply(kTypeInfo, model, fw_major, fw_minor, hardware, serial16);
}

std::string encodeHealth(int status, int error_code) {
  return encodeHealthReply(kTypeHealth, status, error_code);
}

std::string encodePacket(bool ring_start, double first_raw_deg, double last_raw_deg,
                         const std::vector<double>& distances_mm) {
  const auto lsn = static_cast<uint8_t>(std::min<size_t>(distances_mm.size(), 255));
  const uint8_t ct = ring_start ? 1 : 0;
  const uint16_t fsa = encodeAngle(first_raw_deg), lsa = encodeAngle(last_raw_deg);
  std::vector<uint16_t> si(lsn);
  for (size_t i = 0; i < lsn; ++i) {
    const double q = std::clamp(distances_mm[i] * 4.0, 0.0, 65535.0);
    si[i] = static_cast<uint16_t>(std::lround(q));
  }
  uint16_t cs = 0x55AA ^ fsa ^ static_cast<uint16_t>(ct | (lsn << 8)) ^ lsa;
  for (uint16_t v : si) cs ^= v;
  std::string s = "\xAA\x55";
  s.push_back(static_cast<char>(ct));
  s.push_back(static_cast<char>(lsn));
  put16(&s, fsa);
  put16(&s, lsa);
  put16(&s, cs);
  for (uint16_t v : si) put16(&s, v);
  return s;
}

}  // namespace ydlidar
}  // namespace sweepmap
