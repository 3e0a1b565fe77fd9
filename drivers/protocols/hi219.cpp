#include "drivers/protocols/hi219.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace sweepmap {
namespace hi219 {
namespace {

constexpr size_t kHeader = 6;
constexpr size_t kMaxPayload = 512 - kHeader;  // the vendor decoder's buffer
constexpr size_t kImusol = 76;
constexpr double kDeg = M_PI / 180.0;

int16_t i16(const uint8_t* p) { return static_cast<int16_t>(p[0] | (p[1] << 8)); }
uint16_t u16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t u32(const uint8_t* p) {
  return uint32_t{p[0]} | (uint32_t{p[1]} << 8) | (uint32_t{p[2]} << 16) | (uint32_t{p[3]} << 24);
}
float f32(const uint8_t* p) {
  const uint32_t u = u32(p);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
void put32(std::string* s, uint32_t v) {
  for (int i = 0; i < 4; ++i) s->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void putf(std::string* s, double v) {
  const auto f = static_cast<float>(v);
  uint32_t u;
  std::memcpy(&u, &f, 4);
  put32(s, u);
}

}  // namespace

uint16_t crc16(const uint8_t* data, size_t size, uint16_t crc) {
  uint32_t c = crc;
  for (size_t j = 0; j < size; ++j) {
    c ^= uint32_t{data[j]} << 8;
    for (int i = 0; i < 8; ++i) c = (c & 0x8000) ? ((c << 1) ^ 0x1021) : (c << 1);
  }
  return static_cast<uint16_t>(c);
}

void Decoder::reset() {
  counters_ = {};
  buffer_.clear();
}

void Decoder::parsePayload(const uint8_t* p, size_t n, int64_t offset, std::vector<Event>* out) {
  Frame f;
  f.offset = offset;
  f.size = static_cast<int64_t>(kHeader + n);
  size_t at = 0;
  const auto need = [&](size_t k) { return n - at >= k; };
  while (at < n) {
    const uint8_t tag = p[at];
    const uint8_t* d = p + at + 1;
    if (tag == 0x90 && need(2)) {
      f.id = d[0];
      at += 2;
    } else if ((tag == 0xA0 || tag == 0xA1) && need(7)) {
      for (int k = 0; k < 3; ++k) f.accel_m_s2[k] = i16(d + 2 * k) * 1e-3 * kGravity;
      f.has_accel = true;
      at += 7;
    } else if ((tag == 0xB0 || tag == 0xB1) && need(7)) {
      for (int k = 0; k < 3; ++k) f.gyro_rad_s[k] = i16(d + 2 * k) * 0.1 * kDeg;
      f.has_gyro = true;
      at += 7;
    } else if (tag == 0xC0 && need(7)) {
      for (int k = 0; k < 3; ++k) f.mag_ut[k] = i16(d + 2 * k) * 0.1;  // mGauss -> uT
      f.has_mag = true;
      at += 7;
    } else if (tag == 0xD0 && need(7)) {
      f.rpy_rad = {i16(d + 2) * 0.01 * kDeg, i16(d) * 0.01 * kDeg, i16(d + 4) * 0.1 * kDeg};
      f.has_euler = true;
      at += 7;
    } else if (tag == 0xD1 && need(17)) {
      for (int k = 0; k < 4; ++k) f.quat_wxyz[k] = f32(d + 4 * k);
      f.has_quat = true;
      at += 17;
    } else if (tag == 0xF0 && need(5)) {
      f.pressure_pa = f32(d);
      f.has_pressure = true;
      at += 5;
    } else if (tag == 0x91 && need(kImusol)) {
      f.id = d[0];
      f.pressure_pa = f32(d + 3);
      f.time_ms = u32(d + 7);
      for (int k = 0; k < 3; ++k) {
        f.accel_m_s2[k] = f32(d + 11 + 4 * k) * kGravity;
        f.gyro_rad_s[k] = f32(d + 23 + 4 * k) * kDeg;
        f.mag_ut[k] = f32(d + 35 + 4 * k);
        f.rpy_rad[k] = f32(d + 47 + 4 * k) * kDeg;
      }
      for (int k = 0; k < 4; ++k) f.quat_wxyz[k] = f32(d + 59 + 4 * k);
      f.has_accel = f.has_gyro = f.has_mag = f.has_euler = f.has_quat = f.has_pressure =
          f.has_time = true;
      at += kImusol;
    } else {
      ++counters_.device_errors;
      out->push_back(DecodeError{offset + static_cast<int64_t>(kHeader + at),
                                 "HI219 frame: unknown or cut data item 0x" +
                                     std::string(1, "0123456789ABCDEF"[tag >> 4]) +
                                     std::string(1, "0123456789ABCDEF"[tag & 15]) +
                                     "; the rest of the frame skipped"});
      break;
    }
  }
  ++counters_.packets;
  out->push_back(f);
}

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

// 5A A5, the payload's length, its CRC, the payload.
ParseStep Decoder::parseFrame(const uint8_t* p, size_t left, int64_t offset,
                              std::vector<Event>* out) {
  if (const auto not_yet = expectHeader(p, left, 0x5A, 0xA5, kHeader)) return *not_yet;
  const size_t len = u16(p + 2);
  if (len == 0 || len > kMaxPayload) return ParseStep::skip();  // a false sync
  if (left < kHeader + len) return ParseStep::wait();
  uint16_t crc = crc16(p, 4);
  crc = crc16(p + kHeader, len, crc);
  if (crc != u16(p + 4)) {
    return buffer_.dropBadPacket(
        offset, "HI219 frame (" + std::to_string(len) + " bytes): CRC mismatch; frame dropped",
        &counters_, out);
  }
  buffer_.flushSkipped(&counters_, out);
  parsePayload(p + kHeader, len, offset, out);
  return ParseStep::take(kHeader + len);
}

std::string encodeFrame(const std::string& payload) {
  std::string s = "\x5A\xA5";
  s.push_back(static_cast<char>(payload.size() & 0xff));
  s.push_back(static_cast<char>(payload.size() >> 8));
  uint16_t crc = crc16(reinterpret_cast<const uint8_t*>(s.data()), 4);
  crc = crc16(reinterpret_cast<const uint8_t*>(payload.data()), payload.size(), crc);
  s.push_back(static_cast<char>(crc & 0xff));
  s.push_back(static_cast<char>(crc >> 8));
  return s + payload;
}

std::string encodeOldItems(const Frame& f) {
  std::string s;
  const auto put16 = [&](double v) {
    const auto q = static_cast<int16_t>(std::clamp(std::lround(v), -32768L, 32767L));
    s.push_back(static_cast<char>(static_cast<uint16_t>(q) & 0xff));
    s.push_back(static_cast<char>(static_cast<uint16_t>(q) >> 8));
  };
  s.push_back(static_cast<char>(0x90));
  s.push_back(static_cast<char>(f.id < 0 ? 0 : f.id));
  s.push_back(static_cast<char>(0xA0));
  for (double v : f.accel_m_s2) put16(v / kGravity * 1e3);  // mG
  s.push_back(static_cast<char>(0xB0));
  for (double v : f.gyro_rad_s) put16(v / kDeg * 10.0);  // 0.1 deg/s
  s.push_back(static_cast<char>(0xC0));
  for (double v : f.mag_ut) put16(v * 10.0);  // mGauss
  s.push_back(static_cast<char>(0xD0));
  put16(f.rpy_rad[1] / kDeg * 100.0);  // pitch, 0.01 deg
  put16(f.rpy_rad[0] / kDeg * 100.0);  // roll
  put16(f.rpy_rad[2] / kDeg * 10.0);   // yaw, 0.1 deg
  s.push_back(static_cast<char>(0xF0));
  putf(&s, f.pressure_pa);
  return s;
}

std::string encodeImusol(const Frame& f) {
  std::string s;
  s.push_back(static_cast<char>(0x91));
  s.push_back(static_cast<char>(f.id < 0 ? 0 : f.id));
  s.push_back('\0');  // status (reserved)
  s.push_back(25);    // temperature [degC]
  putf(&s, f.pressure_pa);
  put32(&s, f.time_ms);
  for (double v : f.accel_m_s2) putf(&s, v / kGravity);
  for (double v : f.gyro_rad_s) putf(&s, v / kDeg);
  for (double v : f.mag_ut) putf(&s, v);
  for (double v : f.rpy_rad) putf(&s, v / kDeg);
  for (double v : f.quat_wxyz) putf(&s, v);
  return s;
}

}  // namespace hi219
}  // namespace sweepmap
