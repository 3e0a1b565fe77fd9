// YDLIDAR X4 serial protocol (YDLIDAR X4 Development Manual), 128000 baud 8N1, little-endian.
//
// Host -> device: A5 60 start scanning, A5 65 stop, A5 90 device info, A5 91 health,
// A5 80 soft restart. The motor turns while M_EN is high (DTR on the USB adapter).
// Device -> host: a reply starts A5 5A, then 32 bits (low 30: content length, high 2: mode,
// 0 single / 1 continuous), then a type code: 04 device info (20 bytes: model, firmware
// major and minor, hardware, 16-byte serial), 06 health (status, 16-bit error code),
// 81 the start of the scan stream (A5 5A 05 00 00 40 81), followed by sample packets:
//   PH AA 55 | CT (bit 0: 1 = the ring's zero packet, LSN 1) | LSN samples |
//   FSA, LSA (bit 0 is a check bit, 1; angle = (x >> 1) / 64 deg) | CS | LSN x Si
// CS is the XOR of the packet's 16-bit words: PH, FSA, every Si, CT|LSN<<8 and LSA.
// Distance = Si / 4 mm. Sample i's first-level angle interpolates FSA..LSA (across 360),
// by the vendor SDK's rule: LSA < FSA is the wrap only when FSA > 270 deg and LSA < 90 deg,
// otherwise (a real X4 sends such packets) the previous packet's step is kept from FSA and the
// packet counted as an anomaly (Decoder::sampleStep); the second-level, range-dependent correction
// (the X4's triangulation geometry) adds
//   AngCorrect(d) = 0 for d = 0, else atan(21.8 (155.3 - d) / (155.3 d)) [deg], d in mm.
// Angles grow clockwise seen from the top, 0 at the device's front mark. sweepmap's frame
// L: Z_L = the 0 deg mark, Y_L = the 90 deg mark, X_L = the device's top (right-handed), so
// the lidar angle is the device angle wrapped to (-180, 180] deg.
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "drivers/protocols/decoder.hpp"

namespace sweepmap {
namespace ydlidar {

constexpr uint8_t kCmdStart = 0x60, kCmdStop = 0x65, kCmdInfo = 0x90, kCmdHealth = 0x91,
                  kCmdRestart = 0x80;
constexpr uint8_t kTypeInfo = 0x04, kTypeHealth = 0x06, kTypeScan = 0x81;
constexpr int kModelX4 = 6;  // the model code an X4 reports

double angleCorrectionDeg(double distance_mm);

struct DeviceInfo {
  int model = 0;
  int firmware_major = 0, firmware_minor = 0, hardware = 0;
  std::string serial;  // 16 bytes as hex digits
  int64_t offset = 0;
};
struct Health {
  int status = 0;  // 0 ok, 1 warning, 2 error
  int error_code = 0;
  int64_t offset = 0;
};
// The scan stream's descriptor (A5 5A 05 00 00 40 81).
struct ScanStart {
  int64_t offset = 0;
};
struct Sample {
  double angle_deg = 0.0;  // corrected, [0, 360)
  double raw_angle_deg = 0.0;
  double distance_mm = 0.0;  // 0: no return
};
struct Packet {
  bool ring_start = false;  // the zero packet
  std::vector<Sample> samples;
  int64_t offset = 0;      // first byte (AA)
  int64_t end_offset = 0;  // one past the last byte
};

using Event = std::variant<DeviceInfo, Health, ScanStart, Packet, DecodeError>;

class Decoder {
 public:
  void feed(const uint8_t* data, size_t size, std::vector<Event>* out);
  // The end of the input: bytes held for a packet that cannot complete are searched again
  // (PacketBuffer::finish).
  void finish(std::vector<Event>* out);
  const DecoderCounters& counters() const { return counters_; }
  void reset();

 private:
  ParseStep parse(const uint8_t* p, size_t left, int64_t offset, std::vector<Event>* out);
  ParseStep parseReply(const uint8_t* p, size_t left, int64_t offset, std::vector<Event>* out);
  ParseStep parsePacket(const uint8_t* p, size_t left, int64_t offset, std::vector<Event>* out);
  double sampleStep(size_t lsn, uint16_t fsa, uint16_t lsa);
  DecoderCounters counters_;
  double last_step_deg_ =
      0.0;  // the last packet's step (the SDK's IntervalSampleAngle_LastPackage)
  PacketBuffer buffer_{"YDLIDAR", "to the next packet"};
};

// Device side (the emulator): encoders. Angles in degrees [0, 360), raw (uncorrected).
std::string encodeDescriptor(uint32_t length, int mode, uint8_t type);
std::string encodeInfo(int model, int fw_major, int fw_minor, int hardware,
                       const std::string& serial16);
std::string encodeHealth(int status, int error_code);
// One packet; `distances_mm` in mm (quantised to 1/4 mm).
std::string encodePacket(bool ring_start, double first_raw_deg, double last_raw_deg,
                         const std::vector<double>& distances_mm);

}  // namespace ydlidar
}  // namespace sweepmap
