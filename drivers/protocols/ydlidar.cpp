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

}  // namespace

double angleCorrectionDeg(double d) {
  if (d <= 0.0) return 0.0;
  return std::atan(21.8 * (155.3 - d) / (155.3 * d)) * 180.0 / M_PI;
}

void Decoder::reset() {
  counters_ = {};
  buffer_.clear();
  buffer_offset_ = 0;
  skipped_.clear();
}

void Decoder::feed(const uint8_t* data, size_t size, std::vector<Event>* out) {
  counters_.bytes += static_cast<int64_t>(size);
  buffer_.insert(buffer_.end(), data, data + size);
  parse(out, false);
}

void Decoder::parse(std::vector<Event>* out, bool) {
  size_t at = 0;
  const auto flushGarbage = [&] { skipped_.flush(&counters_, out); };
  const auto skip = [&](size_t n) {
    skipped_.skip(buffer_offset_ + static_cast<int64_t>(at), n);
    at += n;
  };
  while (at < buffer_.size()) {
    const size_t left = buffer_.size() - at;
    const uint8_t* p = buffer_.data() + at;
    const int64_t offset = buffer_offset_ + static_cast<int64_t>(at);
    if (p[0] == 0xA5) {
      if (left < 2) break;
      if (p[1] != 0x5A) {
        skip(1);
        continue;
      }
      if (left < kDescriptor) break;
      Descriptor descriptor;
      parseDescriptor(p, &descriptor);
      const uint32_t length = descriptor.length;
      const int mode = descriptor.mode;
      const uint8_t type = descriptor.type;
      if (type == kTypeScan && mode == 1) {
        flushGarbage();
        ++counters_.packets;
        out->push_back(ScanStart{offset});
        at += kDescriptor;
        continue;
      }
      if ((type == kTypeInfo && length == 20 && mode == 0) ||
          (type == kTypeHealth && length == 3 && mode == 0)) {
        if (left < kDescriptor + length) break;
        flushGarbage();
        const uint8_t* c = p + kDescriptor;
        ++counters_.packets;
        if (type == kTypeInfo) {
          DeviceInfo info;
          info.model = c[0];
          info.firmware_major = c[1];  // the manual: low byte major, high byte minor
          info.firmware_minor = c[2];
          info.hardware = c[3];
          for (int i = 0; i < 16; ++i) {
            char hex[3];
            std::snprintf(hex, sizeof hex, "%02X", c[4 + i]);
            info.serial += hex;
          }
          info.offset = offset;
          out->push_back(info);
        } else {
          Health h;
          h.status = c[0];
          h.error_code = le16(c + 1);
          h.offset = offset;
          if (h.status != 0) ++counters_.device_errors;
          out->push_back(h);
        }
        at += kDescriptor + length;
        continue;
      }
      skip(1);  // A5 5A with a descriptor we do not know: a false start
      continue;
    }
    if (p[0] == 0xAA) {
      if (left < 2) break;
      if (p[1] != 0x55) {
        skip(1);
        continue;
      }
      if (left < kHeader) break;
      const uint8_t ct = p[2];
      const size_t lsn = p[3];
      const uint16_t fsa = le16(p + 4), lsa = le16(p + 6), cs = le16(p + 8);
      if (lsn == 0 || (fsa & 1) == 0 || (lsa & 1) == 0 || ((ct & 1) && lsn != 1)) {
        skip(1);  // not a packet header: resynchronise at the next byte
        continue;
      }
      const size_t total = kHeader + 2 * lsn;
      if (left < total) break;
      uint16_t x = le16(p) ^ fsa ^ static_cast<uint16_t>(ct | (lsn << 8)) ^ lsa;
      for (size_t i = 0; i < lsn; ++i) x ^= le16(p + kHeader + 2 * i);
      if (x != cs) {
        // A bad check: the packet is dropped, and its bytes searched again for a real
        // header (the AA 55 may have been a false one inside good data).
        flushGarbage();
        ++counters_.checksum_errors;
        out->push_back(DecodeError{offset, "YDLIDAR packet (LSN " + std::to_string(lsn) +
                                               "): check code mismatch; packet dropped"});
        at += 1;
        ++counters_.resyncs;
        counters_.discarded_bytes += 1;
        continue;
      }
      flushGarbage();
      Packet packet;
      packet.ring_start = ct & 1;
      packet.offset = offset;
      packet.end_offset = offset + static_cast<int64_t>(total);
      const double first = (fsa >> 1) / 64.0, last = (lsa >> 1) / 64.0;
      double span = last - first;
      if (span < 0) span += 360.0;
      for (size_t i = 0; i < lsn; ++i) {
        Sample s;
        s.distance_mm = le16(p + kHeader + 2 * i) / 4.0;
        s.raw_angle_deg = lsn > 1 ? first + span * static_cast<double>(i) / double(lsn - 1) : first;
        double a = s.raw_angle_deg + angleCorrectionDeg(s.distance_mm);
        a = std::fmod(a, 360.0);
        if (a < 0) a += 360.0;
        s.raw_angle_deg = std::fmod(s.raw_angle_deg, 360.0);
        s.angle_deg = a;
        packet.samples.push_back(s);
      }
      ++counters_.packets;
      out->push_back(std::move(packet));
      at += total;
      continue;
    }
    skip(1);
  }
  // Keep only the unparsed tail (bounded: at most one packet header's worth is waited for,
  // a packet is at most 10 + 2 * 255 bytes).
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(at));
  buffer_offset_ += static_cast<int64_t>(at);
  if (buffer_.empty()) flushGarbage();
}

std::string encodeDescriptor(uint32_t length, int mode, uint8_t type) {
  return sweepmap::encodeDescriptor(length, mode, type);
}

std::string encodeInfo(int model, int fw_major, int fw_minor, int hardware,
                       const std::string& serial16) {
  std::string s = encodeDescriptor(20, 0, kTypeInfo);
  s.push_back(static_cast<char>(model));
  s.push_back(static_cast<char>(fw_major));
  s.push_back(static_cast<char>(fw_minor));
  s.push_back(static_cast<char>(hardware));
  for (int i = 0; i < 16; ++i) s.push_back(i < static_cast<int>(serial16.size()) ? serial16[i] : 0);
  return s;
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
