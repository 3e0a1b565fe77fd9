#include "drivers/protocols/rplidar.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "drivers/protocols/descriptor.hpp"

namespace sweepmap {
namespace rplidar {
namespace {

constexpr size_t kDescriptor = 7;
constexpr size_t kSample = 5;

bool validSample(const uint8_t* p) {
  const bool s = p[0] & 1, not_s = (p[0] >> 1) & 1;
  return s != not_s && (p[1] & 1) == 1;
}

bool knownDescriptor(const uint8_t* p, uint32_t* length, int* mode, uint8_t* type) {
  Descriptor d;
  if (!parseDescriptor(p, &d)) return false;
  *length = d.length;
  *mode = d.mode;
  *type = d.type;
  return (*type == kTypeScan && *length == 5 && *mode == 1) ||
         (*type == kTypeInfo && *length == 20 && *mode == 0) ||
         (*type == kTypeHealth && *length == 3 && *mode == 0) ||
         (*type == kTypeSampleRate && *length == 4 && *mode == 0);
}

// The content `c` of a single reply (device info, health or sample rate).
Event decodeReply(uint8_t type, const uint8_t* c, int64_t offset) {
  if (type == kTypeInfo) {
    DeviceInfo i;
    i.model = c[0];
    i.firmware_minor = c[1];
    i.firmware_major = c[2];
    i.hardware = c[3];
    i.serial = hexBytes(c + 4, 16);
    i.offset = offset;
    return i;
  }
  if (type == kTypeHealth) {
    Health h;
    h.status = c[0];
    h.error_code = c[1] | (c[2] << 8);
    h.offset = offset;
    return h;
  }
  SampleRate r;
  r.standard_us = c[0] | (c[1] << 8);
  r.express_us = c[2] | (c[3] << 8);
  r.offset = offset;
  return r;
}

}  // namespace

void Decoder::reset() {
  counters_ = {};
  buffer_.clear();
  scanning_ = false;
}

ParseStep Decoder::parse(const uint8_t* p, size_t left, int64_t offset, std::vector<Event>* out) {
  if (p[0] == 0xA5) {
    if (const auto step = parseReply(p, left, offset, out)) return *step;
  }
  return parseSample(p, left, offset, out);
}

void Decoder::feed(const uint8_t* data, size_t size, std::vector<Event>* out) {
  const bool all_taken = buffer_.feed(
      data, size, &counters_,
      [&](const uint8_t* p, size_t left, int64_t offset) { return parse(p, left, offset, out); });
  flushBatch(out);
  if (all_taken) flushSkipped(out);
}

void Decoder::finish(std::vector<Event>* out) {
  std::vector<Event> skipped;
  buffer_.finish(&counters_, &skipped, [&](const uint8_t* p, size_t left, int64_t offset) {
    return parse(p, left, offset, out);
  });
  flushBatch(out);  // the samples go out before the error that follows them
  out->insert(out->end(), skipped.begin(), skipped.end());
}

void Decoder::flushBatch(std::vector<Event>* out) {
  if (!batch_.samples.empty()) out->push_back(std::move(batch_));
  batch_ = Samples{};
}

// The samples decoded so far go out before the error that follows them.
void Decoder::flushSkipped(std::vector<Event>* out) {
  if (buffer_.skippedNone()) return;
  flushBatch(out);
  buffer_.flushSkipped(&counters_, out);
}

// A5 5A and a descriptor this host knows, with its reply; nothing when the bytes are not one
// (while scanning, an A5 may start a sample).
std::optional<ParseStep> Decoder::parseReply(const uint8_t* p, size_t left, int64_t offset,
                                             std::vector<Event>* out) {
  if (left < kDescriptor) {
    if (!scanning_ || left < 2 || p[1] == 0x5A) return ParseStep::wait();
    return std::nullopt;
  }
  uint32_t length = 0;
  int mode = 0;
  uint8_t type = 0;
  if (!knownDescriptor(p, &length, &mode, &type)) return std::nullopt;
  if (type != kTypeScan && left < kDescriptor + length) return ParseStep::wait();
  flushSkipped(out);
  flushBatch(out);
  ++counters_.packets;
  scanning_ = type == kTypeScan;
  if (scanning_) {
    out->push_back(ScanStart{offset});
    return ParseStep::take(kDescriptor);
  }
  out->push_back(decodeReply(type, p + kDescriptor, offset));
  if (type == kTypeHealth && std::get<Health>(out->back()).status != 0) ++counters_.device_errors;
  return ParseStep::take(kDescriptor + length);
}

// A 5-byte sample of the scan stream, added to the batch.
ParseStep Decoder::parseSample(const uint8_t* p, size_t left, int64_t offset,
                               std::vector<Event>* out) {
  if (!scanning_) return ParseStep::skip();
  if (left < kSample) return ParseStep::wait();
  if (!validSample(p)) return ParseStep::skip();
  flushSkipped(out);
  Sample s;
  s.start = p[0] & 1;
  s.quality = p[0] >> 2;
  s.angle_deg = ((p[1] >> 1) | (p[2] << 7)) / 64.0;
  s.distance_mm = (p[3] | (p[4] << 8)) / 4.0;
  s.end_offset = offset + static_cast<int64_t>(kSample);
  if (s.angle_deg >= 360.0) return ParseStep::skip();  // angle_q6 beyond a turn: not a sample
  ++counters_.packets;
  batch_.samples.push_back(s);
  return ParseStep::take(kSample);
}

std::string request(uint8_t cmd, const std::string& payload) {
  std::string s = {static_cast<char>(0xA5), static_cast<char>(cmd)};
  if (!payload.empty()) {
    s.push_back(static_cast<char>(payload.size()));
    s += payload;
    uint8_t x = 0;
    for (char c : s) x ^= static_cast<uint8_t>(c);
    s.push_back(static_cast<char>(x));
  }
  return s;
}

std::string encodeDescriptor(uint32_t length, int mode, uint8_t type) {
  return sweepmap::encodeDescriptor(length, mode, type);
}

std::string encodeInfo(int model, int fw_major, int fw_minor, int hardware,
                       const std::string& serial16) {
  return encodeInfoReply(kTypeInfo, model, fw_minor, fw_major, hardware, serial16);
}

std::string encodeHealth(int status, int error_code) {
  return encodeHealthReply(kTypeHealth, status, error_code);
}

std::string encodeSample(bool start, int quality, double angle_deg, double distance_mm) {
  double a = std::fmod(angle_deg, 360.0);
  if (a < 0) a += 360.0;
  int q6 = static_cast<int>(std::lround(a * 64.0));
  if (q6 >= 360 * 64) q6 -= 360 * 64;
  const auto q2 = static_cast<uint16_t>(std::clamp(std::lround(distance_mm * 4.0), 0L, 65535L));
  std::string s(5, '\0');
  s[0] = static_cast<char>((std::clamp(quality, 0, 63) << 2) | ((start ? 0 : 1) << 1) |
                           (start ? 1 : 0));
  s[1] = static_cast<char>(((q6 & 0x7f) << 1) | 1);
  s[2] = static_cast<char>((q6 >> 7) & 0xff);
  s[3] = static_cast<char>(q2 & 0xff);
  s[4] = static_cast<char>(q2 >> 8);
  return s;
}

void RequestParser::feed(const uint8_t* data, size_t size, std::vector<Request>* out) {
  buffer_.insert(buffer_.end(), data, data + size);
  size_t at = 0;
  while (at < buffer_.size()) {
    if (buffer_[at] != 0xA5) {
      ++at;
      continue;
    }
    if (buffer_.size() - at < 2) break;
    const uint8_t cmd = buffer_[at + 1];
    // Commands with a payload have bit 7 set (EXPRESS_SCAN 0x82, SET_MOTOR_PWM 0xF0, ...).
    if (cmd & 0x80) {
      if (buffer_.size() - at < 3) break;
      const size_t n = buffer_[at + 2];
      if (buffer_.size() - at < 4 + n) break;
      uint8_t x = 0;
      for (size_t i = 0; i < 3 + n; ++i) x ^= buffer_[at + i];
      if (x == buffer_[at + 3 + n]) {
        out->push_back(
            Request{cmd, std::string(buffer_.begin() + static_cast<std::ptrdiff_t>(at + 3),
                                     buffer_.begin() + static_cast<std::ptrdiff_t>(at + 3 + n))});
        at += 4 + n;
      } else {
        ++at;
      }
      continue;
    }
    out->push_back(Request{cmd, {}});
    at += 2;
  }
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(at));
  if (buffer_.size() > 1024) buffer_.clear();
}

}  // namespace rplidar
}  // namespace sweepmap
