// Slamtec RPLIDAR A1/A2 serial protocol ("RPLIDAR Interface Protocol and Application
// Notes"), 115200 baud 8N1 (A1/A2; 256000 for A3), little-endian.
//
// Host -> device: A5 cmd, or A5 cmd size payload checksum (XOR of every byte before it) for
// commands with a payload: 25 STOP, 40 RESET, 20 SCAN, 21 FORCE_SCAN, 50 GET_INFO,
// 52 GET_HEALTH, 59 GET_SAMPLERATE, F0 SET_MOTOR_PWM (A2). The A1's motor runs while DTR
// is low on its USB adapter board (MOTOCTL); sweepmap drives DTR so that it runs.
// Device -> host: a response descriptor A5 5A, 32 bits (low 30: length, high 2: send mode,
// 0 single / 1 multiple), a data type: 04 info (model, firmware minor, firmware major,
// hardware, 16-byte serial), 06 health (status 0 good / 1 warning / 2 error, error code),
// 15 sample rate, 81 scan: then 5-byte samples, forever:
//   byte 0: quality (6 bits) << 2 | !S << 1 | S   (S = 1: the first sample of a new turn)
//   byte 1: angle_q6 bits 0..6 << 1 | C (C = 1)   byte 2: angle_q6 bits 7..14
//   bytes 3-4: distance_q2 (mm * 4), 0 = no return.
// A sample whose S and !S are equal or whose C is 0 is not a sample: the decoder moves on
// by one byte. Angles grow clockwise seen from the top, 0 at the front (the lidar frame as
// for the X4: drivers/protocols/ydlidar.hpp). Express and boost modes are not decoded.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "drivers/protocols/decoder.hpp"

namespace sweepmap {
namespace rplidar {

constexpr uint8_t kCmdStop = 0x25, kCmdReset = 0x40, kCmdScan = 0x20, kCmdForceScan = 0x21,
                  kCmdInfo = 0x50, kCmdHealth = 0x52, kCmdSampleRate = 0x59, kCmdMotorPwm = 0xF0;
constexpr uint8_t kTypeInfo = 0x04, kTypeHealth = 0x06, kTypeSampleRate = 0x15, kTypeScan = 0x81;

struct DeviceInfo {
  int model = 0, firmware_major = 0, firmware_minor = 0, hardware = 0;
  std::string serial;  // hex
  int64_t offset = 0;
};
struct Health {
  int status = 0, error_code = 0;
  int64_t offset = 0;
};
struct SampleRate {
  int standard_us = 0, express_us = 0;
  int64_t offset = 0;
};
struct ScanStart {
  int64_t offset = 0;
};
struct Sample {
  bool start = false;  // S: the first sample of a new turn
  int quality = 0;
  double angle_deg = 0.0;
  double distance_mm = 0.0;
  int64_t end_offset = 0;  // one past its last byte
};
// Consecutive samples decoded from one feed() (batched to keep events few).
struct Samples {
  std::vector<Sample> samples;
};

using Event = std::variant<DeviceInfo, Health, SampleRate, ScanStart, Samples, DecodeError>;

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
  std::optional<ParseStep> parseReply(const uint8_t* p, size_t left, int64_t offset,
                                      std::vector<Event>* out);
  ParseStep parseSample(const uint8_t* p, size_t left, int64_t offset, std::vector<Event>* out);
  void flushBatch(std::vector<Event>* out);
  void flushSkipped(std::vector<Event>* out);
  DecoderCounters counters_;
  PacketBuffer buffer_{"RPLIDAR", "(bad start or check bits)"};
  bool scanning_ = false;  // after a scan descriptor: 5-byte samples
  Samples batch_;          // the samples of this feed() so far
};

// Host side.
std::string request(uint8_t cmd, const std::string& payload = {});
// Device side (the emulator).
std::string encodeDescriptor(uint32_t length, int mode, uint8_t type);
std::string encodeInfo(int model, int fw_major, int fw_minor, int hardware,
                       const std::string& serial16);
std::string encodeHealth(int status, int error_code);
std::string encodeSample(bool start, int quality, double angle_deg, double distance_mm);

// Device side: parses host requests (A5 cmd [size payload checksum]); a request with a bad
// checksum or an unknown command is dropped (the device ignores it).
struct Request {
  uint8_t cmd = 0;
  std::string payload;
};
class RequestParser {
 public:
  void feed(const uint8_t* data, size_t size, std::vector<Request>* out);

 private:
  std::vector<uint8_t> buffer_;
};

}  // namespace rplidar
}  // namespace sweepmap
