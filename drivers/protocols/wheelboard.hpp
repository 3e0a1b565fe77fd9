// The wheel board protocol: sweepmap's own binary serial protocol between the host and the
// small microcontroller (an STM32) that reads rig B's wheel encoders and drives its motors.
// This header is its specification.
//
// Link: a UART (USB CDC on the board: /dev/ttyACM0), 115200 baud 8N1; every number
// little-endian. Frames, both ways:
//
//   offset  size  field
//   0       2     sync: 0xA5 0x5B
//   2       1     type: 0x01 TICKS (board -> host), 0x02 SPEED (host -> board)
//   3       1     payload length n (TICKS: 14, SPEED: 4; others reserved, up to 64)
//   4       2     sequence number: per direction, +1 per frame, wrapping at 65536
//   6       n     payload
//   6+n     2     CRC-16/CCITT-FALSE (polynomial 0x1021, initial 0xFFFF, no reflection, no
//                 final XOR; check value 0x29B1 for "123456789") over bytes 2 .. 5+n
//
// TICKS payload (the board sends one every 10-20 ms: 50-100 Hz, at the encoder read):
//   uint32 time_us   the board's microsecond clock at the read (wraps every 71.6 min)
//   int32  left      cumulative encoder counts of the left wheel (wraps as int32)
//   int32  right     cumulative encoder counts of the right wheel
//   uint16 flags     bit 0: motors stopped by the watchdog (no SPEED for 0.5 s);
//                    bit 1 / 2: left / right encoder fault; bit 3: motor driver fault;
//                    bit 4: battery low; bits 5-15: 0
// SPEED payload (the host sends WHEEL_CMD at 10-50 Hz):
//   int16  v_mm_s       linear velocity [mm/s], forward positive
//   int16  w_mrad_s     angular velocity [mrad/s], counter-clockwise (left turn) positive
// Watchdog: a board that receives no valid SPEED frame for 0.5 s sets both wheel speeds to
// zero and raises flag bit 0 until the next one. A frame with a bad CRC is ignored by
// either side; the receiver counts it and resynchronises at the next 0xA5 0x5B. A gap in
// the sequence numbers counts the frames lost.
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "drivers/protocols/decoder.hpp"

namespace sweepmap {
namespace wheelboard {

constexpr uint8_t kTypeTicks = 0x01, kTypeSpeed = 0x02;
constexpr int64_t kTicksFrameBytes = 22, kSpeedFrameBytes = 12;  // sync to CRC
constexpr uint16_t kFlagWatchdog = 1 << 0, kFlagLeftEncoder = 1 << 1, kFlagRightEncoder = 1 << 2,
                   kFlagDriver = 1 << 3, kFlagBattery = 1 << 4;

uint16_t crc16(const uint8_t* data, size_t size);

struct Ticks {
  uint16_t seq = 0;
  uint32_t time_us = 0;
  int32_t left = 0, right = 0;
  uint16_t flags = 0;
  int64_t offset = 0;
};
struct Speed {
  uint16_t seq = 0;
  double v_m_s = 0.0, w_rad_s = 0.0;
  int64_t offset = 0;
};

using Event = std::variant<Ticks, Speed, DecodeError>;

class Decoder {
 public:
  void feed(const uint8_t* data, size_t size, std::vector<Event>* out);
  // The end of the input: bytes held for a packet that cannot complete are searched again
  // (PacketBuffer::finish).
  void finish(std::vector<Event>* out);
  const DecoderCounters& counters() const { return counters_; }
  // Frames lost, from the gaps in the sequence numbers (per frame type).
  int64_t sequenceGaps() const { return gaps_; }
  void reset();

 private:
  ParseStep parseFrame(const uint8_t* p, size_t left, int64_t offset, std::vector<Event>* out);
  void decodeFrame(const uint8_t* p, int64_t offset, std::vector<Event>* out);
  DecoderCounters counters_;
  PacketBuffer buffer_{"wheel board", "to the next frame"};
  bool have_seq_[3] = {false, false, false};
  uint16_t last_seq_[3] = {0, 0, 0};
  int64_t gaps_ = 0;
};

std::string encodeTicks(const Ticks& t);
// Velocities are rounded to mm/s and mrad/s and clamped to int16.
std::string encodeSpeed(uint16_t seq, double v_m_s, double w_rad_s);

}  // namespace wheelboard
}  // namespace sweepmap
