// The response descriptor that RPLIDAR and YDLIDAR share: A5 5A, 32 bits little-endian (low
// 30: content length, high 2: mode, 0 single / 1 continuous), a type code.
#pragma once

#include <cstdint>
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

}  // namespace sweepmap
