// HiPNUC HI219 (and its HI2xx family) serial protocol, from the vendor's user manual
// (section 6.3) and decoder (hipnuc/products, hipnuc_dec.c). 115200 baud 8N1 by default,
// little-endian.
//
// Frame: 5A A5 | payload length (16 bits) | CRC (16 bits) | payload. The CRC is CRC-16 with
// polynomial 0x1021, initial value 0, no reflection (XMODEM), over the first four bytes and
// the payload. The payload is a sequence of data items, each a tag then its data:
//   0x90 user ID (1 byte)
//   0xA0 acceleration, 3 x int16, mG            0xB0 angular rate, 3 x int16, 0.1 deg/s
//   0xC0 magnetic field, 3 x int16, mGauss      0xD0 Euler angles: pitch, roll (int16, 0.01 deg),
//                                                    yaw (int16, 0.1 deg)
//   0xD1 quaternion w, x, y, z (4 x float)      0xF0 air pressure (float, Pa)
//   0x91 the combined record (76 bytes): tag, ID, status and temperature, pressure (float, Pa),
//        time stamp (uint32, ms), acceleration (3 x float, G), angular rate (3 x float,
//        deg/s), magnetic field (3 x float, uT), roll, pitch, yaw (3 x float, deg),
//        quaternion w, x, y, z (4 x float).
// Values here are SI: m/s^2 (1 G = 9.80665 m/s^2), rad/s, rad, uT, Pa. An unknown tag ends
// the frame's parsing (its length is unknown): the items before it are kept and the rest
// counted as a device error.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "drivers/protocols/decoder.hpp"

namespace sweepmap {
namespace hi219 {

constexpr double kGravity = 9.80665;  // m/s^2 per G

uint16_t crc16(const uint8_t* data, size_t size, uint16_t crc = 0);

struct Frame {
  int id = -1;  // 0x90 or 0x91; -1 if none
  bool has_accel = false, has_gyro = false, has_mag = false, has_euler = false, has_quat = false,
       has_pressure = false, has_time = false;
  std::array<double, 3> accel_m_s2{}, gyro_rad_s{}, mag_ut{};
  std::array<double, 3> rpy_rad{};  // roll, pitch, yaw
  std::array<double, 4> quat_wxyz{};
  double pressure_pa = 0.0;
  uint32_t time_ms = 0;  // the IMU's own clock (0x91)
  int64_t offset = 0;    // of the frame's first byte
  int64_t size = 0;      // of the whole frame, header and CRC included
};

using Event = std::variant<Frame, DecodeError>;

class Decoder {
 public:
  void feed(const uint8_t* data, size_t size, std::vector<Event>* out);
  // The end of the input: the bytes held for a frame that cannot complete are searched again
  // (PacketBuffer::finish).
  void finish(std::vector<Event>* out);
  const DecoderCounters& counters() const { return counters_; }
  void reset();

 private:
  void parsePayload(const uint8_t* p, size_t n, int64_t offset, std::vector<Event>* out);
  ParseStep parseFrame(const uint8_t* p, size_t left, int64_t offset, std::vector<Event>* out);
  DecoderCounters counters_;
  PacketBuffer buffer_{"HI219", "to the next frame"};
};

// Device side (the emulator): a frame of the given payload, with its CRC.
std::string encodeFrame(const std::string& payload);
// The 0x91 record of `f` (SI values back to the record's units).
std::string encodeImusol(const Frame& f);
// The old item set of `f`, as an HI219 sends by default: 0x90 ID, 0xA0 acceleration, 0xB0
// angular rate, 0xC0 magnetic field, 0xD0 Euler angles, 0xF0 pressure (the manual's sample
// frame, section 6.3.4.1); values rounded to the items' units.
std::string encodeOldItems(const Frame& f);

}  // namespace hi219
}  // namespace sweepmap
