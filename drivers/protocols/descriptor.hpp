// The response descriptor that RPLIDAR and YDLIDAR share: A5 5A, 32 bits little-endian (low
// 30: content length, high 2: mode, 0 single / 1 continuous), a type code.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace sweepmap {

struct Descriptor {
  uint32_t length = 0;
  int mode = 0;
  uint8_t type = 0;
};
constexpr size_t kDescriptorBytes = 7;

inline std::string encodeDescriptor(uint32_t length, int mode, uint8_t type) {
  std::string s = "\xA5\x5A";
  const uint32_t word = (length & 0x3FFFFFFF) | (static_cast<uint32_t>(mode) << 30);
  for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>((word >> (8 * i)) & 0xff));
  s.push_back(static_cast<char>(type));
  return s;
}

// `p` holds at least kDescriptorBytes; false unless it starts A5 5A.
inline bool parseDescriptor(const uint8_t* p, Descriptor* d) {
  if (p[0] != 0xA5 || p[1] != 0x5A) return false;
  const uint32_t word = static_cast<uint32_t>(p[2] | (p[3] << 8) | (p[4] << 16) | (p[5] << 24));
  d->length = word & 0x3FFFFFFF;
  d->mode = static_cast<int>(word >> 30);
  d->type = p[6];
  return true;
}

// Both devices' health reply: status (0 ok, 1 warning, 2 error), a 16-bit error code.
inline std::string encodeHealthReply(uint8_t type, int status, int error_code) {
  std::string s = encodeDescriptor(3, 0, type);
  s.push_back(static_cast<char>(status));
  s.push_back(static_cast<char>(error_code & 0xff));
  s.push_back(static_cast<char>((error_code >> 8) & 0xff));
  return s;
}

// Both devices' device info reply: the model, two firmware bytes (RPLIDAR: minor, major;
// YDLIDAR: major, minor), the hardware version and a 16-byte serial (zero-padded).
inline std::string encodeInfoReply(uint8_t type, int model, int firmware_byte1, int firmware_byte2,
                                   int hardware, const std::string& serial16) {
  std::string s = encodeDescriptor(20, 0, type);
  s.push_back(static_cast<char>(model));
  s.push_back(static_cast<char>(firmware_byte1));
  s.push_back(static_cast<char>(firmware_byte2));
  s.push_back(static_cast<char>(hardware));
  for (int i = 0; i < 16; ++i) s.push_back(i < static_cast<int>(serial16.size()) ? serial16[i] : 0);
  return s;
}

// The info reply's serial: `n` bytes as upper-case hex digits.
inline std::string hexBytes(const uint8_t* p, int n) {
  std::string s;
  for (int i = 0; i < n; ++i) {
    char h[3];
    std::snprintf(h, sizeof h, "%02X", p[i]);
    s += h;
  }
  return s;
}

}  // namespace sweepmap
