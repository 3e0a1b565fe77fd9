#include "drivers/protocols/scip.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sweepmap {
namespace scip {
namespace {

constexpr size_t kMaxLine = 128;       // a data block is 65 characters; echo/info lines less
constexpr size_t kMaxBodyLines = 400;  // ME over 1081 steps: 102 blocks
constexpr int kStampChars = 4;

bool isCommandLetter(char c) { return c >= 'A' && c <= 'Z'; }
bool isDigit(char c) { return c >= '0' && c <= '9'; }

bool isScanCommand(const std::string& c) {
  return c == "MD" || c == "MS" || c == "ME" || c == "GD" || c == "GS" || c == "GE";
}
bool isStream(const std::string& c) { return c == "MD" || c == "MS" || c == "ME"; }
int charsPerValue(const std::string& c) { return (c == "MS" || c == "GS") ? 2 : 3; }
bool hasIntensity(const std::string& c) { return c == "ME" || c == "GE"; }

// The commands this decoder knows, with the length of their parameters.
int parameterLength(const std::string& c) {
  if (isStream(c)) return 13;                          // start 4, end 4, cluster 2, skip 1, scans 2
  if (c == "GD" || c == "GS" || c == "GE") return 10;  // start 4, end 4, cluster 2
  if (c == "TM") return 1;
  if (c == "SS") return 6;
  if (c == "CR" || c == "HS") return 2;  // HS: 1 (we accept 1 or 2 below)
  if (c == "VV" || c == "PP" || c == "II" || c == "BM" || c == "QT" || c == "RS" || c == "RT" ||
      c == "RB") {
    return 0;
  }
  return -1;
}

// An echo line: a known command, its parameters (digits), an optional ";tag".
bool validEcho(std::string_view line) {
  if (line.size() < 2 || !isCommandLetter(line[0]) || !isCommandLetter(line[1])) return false;
  const std::string c(line.substr(0, 2));
  // An unknown command is echoed too (with status 0D/0E): any two capitals; the status line
  // that must follow, with its checksum, keeps garbage from passing for a reply.
  const int n = parameterLength(c);
  std::string_view rest = line.substr(2);
  const size_t semi = rest.find(';');
  std::string_view params = rest.substr(0, semi);
  if (semi != std::string_view::npos && rest.size() - semi - 1 > 16) return false;
  if (c == "HS") return params.size() == 1 && isDigit(params[0]);
  // Error replies echo what was sent, however malformed: accept any printable parameters
  // of a plausible length, but a scan command's must be its own length (streams are the
  // bulk of the traffic and garbage must not pass for them).
  if (n >= 0 && (isScanCommand(c) || c == "TM")) {
    // A malformed command is echoed as sent (with its error status): up to the full length.
    return params.size() <= static_cast<size_t>(n) &&
           std::all_of(params.begin(), params.end(),
                       [](char ch) { return ch > 0x20 && ch < 0x7f; });
  }
  return params.size() <= 16 &&
         std::all_of(params.begin(), params.end(), [](char ch) { return ch >= 0x20 && ch < 0x7f; });
}

// A data line with its checksum; VV/PP/II lines' checksums cover the text before the ';'.
bool bodyLineOk(const std::string& command, std::string_view text) {
  if (text.size() < 2) return false;
  std::string_view data = text.substr(0, text.size() - 1);
  const bool info = command == "VV" || command == "PP" || command == "II";
  if (info && !data.empty() && data.back() == ';') data.remove_suffix(1);
  return checksum(data) == text.back();
}

bool validStatus(std::string_view line) {
  return line.size() == 3 && line[0] >= 0x30 && line[0] <= 0x7a && line[1] >= 0x30 &&
         line[1] <= 0x7a && checksum(line.substr(0, 2)) == line[2];
}

int digits(std::string_view s, size_t at, size_t n) {
  int v = 0;
  for (size_t i = at; i < at + n; ++i) {
    if (i >= s.size() || !isDigit(s[i])) return -1;
    v = v * 10 + (s[i] - '0');
  }
  return v;
}

}  // namespace

std::string encodeValue(uint32_t value, int chars) {
  chars = std::clamp(chars, 1, 4);
  const uint32_t max = (1u << (6 * chars)) - 1;
  value = std::min(value, max);
  std::string out(static_cast<size_t>(chars), '0');
  for (int i = chars - 1; i >= 0; --i) {
    out[static_cast<size_t>(i)] = static_cast<char>((value & 0x3f) + 0x30);
    value >>= 6;
  }
  return out;
}

std::optional<uint32_t> decodeValue(std::string_view chars) {
  if (chars.empty() || chars.size() > 4) return std::nullopt;
  uint32_t v = 0;
  for (char c : chars) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x30 || u > 0x6f) return std::nullopt;
    v = (v << 6) | (u - 0x30);
  }
  return v;
}

char checksum(std::string_view bytes) {
  unsigned sum = 0;
  for (char c : bytes) sum += static_cast<unsigned char>(c);
  return static_cast<char>((sum & 0x3f) + 0x30);
}

std::string withChecksum(std::string_view data) {
  std::string s(data);
  s.push_back(checksum(data));
  return s;
}

std::string statusText(const std::string& command, const std::string& status) {
  // Common to every command (the specification's "common status").
  static const std::map<std::string, std::string> common = {
      {"0A", "unable to create transmission data or reply command internally"},
      {"0B", "buffer shortage, or a command already being processed was repeated"},
      {"0C", "command with insufficient parameters (1)"},
      {"0D", "undefined command (1)"},
      {"0E", "undefined command (2)"},
      {"0F", "command with insufficient parameters (2)"},
      {"0G", "string in the command exceeds 16 characters"},
      {"0H", "string in the command has invalid characters"},
      {"0I", "sensor is in firmware update mode"},
  };
  if (auto it = common.find(status); it != common.end()) return it->second;
  const auto range = [&](int lo, int hi) {
    const int v = digits(status, 0, 2);
    return v >= lo && v <= hi;
  };
  if (isScanCommand(command)) {
    if (status == "00") return isStream(command) ? "command received, streaming" : "ok";
    if (status == "99" && isStream(command)) return "scan data";
    if (status == "01") return "starting step has a non-numeric value";
    if (status == "02") return "end step has a non-numeric value";
    if (status == "03") return "cluster count has a non-numeric value";
    if (status == "04") return "end step is out of range";
    if (status == "05") return "end step is smaller than the starting step";
    if (isStream(command) && status == "06") return "scan interval has a non-numeric value";
    if (isStream(command) && status == "07") return "number of scans has a non-numeric value";
    if (!isStream(command) && status == "10") return "laser is off";
    if (isStream(command) && range(21, 49)) return "processing stopped to verify an error";
    if (range(50, 97)) return "hardware trouble (laser, motor or other malfunction)";
    if (isStream(command) && status == "98") return "resumed after confirming normal operation";
  } else if (command == "BM") {
    if (status == "00") return "ok: laser on";
    if (status == "01") return "unable to control the laser: laser malfunction";
    if (status == "02") return "laser is already on";
  } else if (command == "TM") {
    if (status == "00") return "ok";
    if (status == "01") return "invalid control code";
    if (status == "02") return "adjust mode is already on";
    if (status == "03") return "adjust mode is off (send TM0 first)";
  } else if (command == "SS") {
    if (status == "00") return "ok";
    if (status == "01") return "bit rate has a non-numeric value";
    if (status == "02") return "invalid bit rate";
    if (status == "03") return "sensor is already at that bit rate";
    if (status == "04") return "not compatible with the sensor";
  } else if (command == "CR") {
    if (status == "00") return "ok";
    if (status == "01") return "invalid speed";
    if (status == "02") return "speed out of range";
    if (status == "03") return "motor is already at that speed";
    if (status == "04") return "not compatible with the sensor";
  } else if (command == "HS") {
    if (status == "00") return "ok";
    if (status == "01") return "invalid parameter";
    if (status == "02") return "already in that mode";
    if (status == "03") return "incompatible with the current settings";
  } else if (command == "RB") {
    if (status == "00") return "ok: rebooting";
    if (status == "01") return "first RB received: send it again within 1 s to reboot";
  } else if (status == "00") {
    return "ok";
  }
  return "unknown status";
}

void Decoder::reset() {
  counters_ = {};
  partial_.clear();
  partial_offset_ = 0;
  partial_too_long_ = false;
  state_ = State::kEcho;
  body_.clear();
  garbage_bytes_ = 0;
}

void Decoder::discard(int64_t offset, size_t bytes, const std::string& why,
                      std::vector<Event>* out) {
  if (bytes == 0) return;
  counters_.discarded_bytes += static_cast<int64_t>(bytes);
  // A run of bad lines (a reply whose line end was corrupted falls apart into many) is one
  // resynchronisation and one error.
  if (garbage_bytes_ > 0 && offset == garbage_offset_ + garbage_bytes_) {
    garbage_bytes_ += static_cast<int64_t>(bytes);
    return;
  }
  flushGarbage(out);
  ++counters_.resyncs;
  garbage_offset_ = offset;
  garbage_bytes_ = static_cast<int64_t>(bytes);
  garbage_why_ = why;
}

void Decoder::flushGarbage(std::vector<Event>* out) {
  if (garbage_bytes_ == 0) return;
  out->push_back(DecodeError{
      garbage_offset_,
      "SCIP: " + garbage_why_ + " (" + std::to_string(garbage_bytes_) + " bytes skipped)"});
  garbage_bytes_ = 0;
}

void Decoder::feed(const uint8_t* data, size_t size, std::vector<Event>* out) {
  for (size_t i = 0; i < size; ++i) {
    const char c = static_cast<char>(data[i]);
    const int64_t at = counters_.bytes++;
    if (c == '\n') {
      std::string_view text(partial_);
      if (!text.empty() && text.back() == '\r') text.remove_suffix(1);  // CR LF
      if (partial_too_long_) {
        discard(partial_offset_, static_cast<size_t>(at - partial_offset_ + 1),
                "line longer than any reply's", out);
        state_ = State::kEcho;
        body_.clear();
      } else {
        line(text, partial_offset_, out);
      }
      partial_.clear();
      partial_too_long_ = false;
      partial_offset_ = at + 1;
      continue;
    }
    if (partial_.size() >= kMaxLine) {
      // Garbage without line ends: keep only its length (counted when the line ends).
      partial_too_long_ = true;
      partial_.resize(kMaxLine);  // bounded memory
      continue;
    }
    partial_.push_back(c);
  }
  flushGarbage(out);
}

bool Decoder::startReply(std::string_view echo, int64_t offset, std::vector<Event>* out) {
  if (validEcho(echo)) {
    flushGarbage(out);
    echo_ = std::string(echo);
    reply_offset_ = offset;
    state_ = State::kStatus;
    return true;
  }
  // Garbage before an echo: resynchronise at the first position where a valid echo starts.
  for (size_t k = 1; k + 2 <= echo.size(); ++k) {
    if (validEcho(echo.substr(k))) {
      discard(offset, k, "garbage before a reply", out);
      flushGarbage(out);
      echo_ = std::string(echo.substr(k));
      reply_offset_ = offset + static_cast<int64_t>(k);
      state_ = State::kStatus;
      return true;
    }
  }
  return false;
}

void Decoder::line(std::string_view text, int64_t offset, std::vector<Event>* out) {
  switch (state_) {
    case State::kEcho:
      if (text.empty()) return;  // an empty line between replies: nothing lost
      if (!startReply(text, offset, out)) {
        discard(offset, text.size() + 1, "not a reply: '" + std::string(text.substr(0, 20)) + "'",
                out);
      }
      return;
    case State::kStatus:
      if (validStatus(text)) {
        status_ = std::string(text.substr(0, 2));
        body_.clear();
        state_ = State::kBody;
        return;
      }
      if (text.size() == 3 && validEcho(echo_) && text[2] != checksum(text.substr(0, 2))) {
        ++counters_.checksum_errors;
        out->push_back(DecodeError{offset, "SCIP " + echo_.substr(0, 2) + " reply: status '" +
                                               std::string(text) + "' fails its checksum"});
        state_ = State::kEcho;
        return;
      }
      // Not a status: the echo was garbage that looked like one; this line may start a reply.
      discard(reply_offset_, echo_.size() + 1, "echo without a status line", out);
      state_ = State::kEcho;
      line(text, offset, out);
      return;
    case State::kBody:
      if (text.empty()) {
        finishReply(out);
        state_ = State::kEcho;
        return;
      }
      // A lost LF LF: a line that fails as data but is the echo of a known command.
      if (!bodyLineOk(echo_.substr(0, 2), text) && validEcho(text) &&
          parameterLength(std::string(text.substr(0, 2))) >= 0) {
        ++counters_.checksum_errors;
        out->push_back(DecodeError{reply_offset_, "SCIP " + echo_.substr(0, 2) +
                                                      " reply: not terminated (lost line end)"});
        body_.clear();
        state_ = State::kEcho;
        line(text, offset, out);
        return;
      }
      if (body_.size() >= kMaxBodyLines) {
        discard(reply_offset_, static_cast<size_t>(offset - reply_offset_),
                "reply longer than any valid one", out);
        body_.clear();
        state_ = State::kEcho;
        return;
      }
      body_.emplace_back(std::string(text), offset);
      return;
  }
}

void Decoder::finishReply(std::vector<Event>* out) {
  const std::string command = echo_.substr(0, 2);
  const std::string where = "SCIP " + command + " reply";
  if (!bodyChecksumsOk(command, where, out)) return;
  const bool data_status = (isStream(command) && status_ == "99") ||
                           (!isStream(command) && isScanCommand(command) && status_ == "00");
  if (isScanCommand(command) && data_status) return emitScan(command, where, out);
  emitReply(command, where, out);
}

// Every body line ends with its checksum; the first that fails drops the reply.
bool Decoder::bodyChecksumsOk(const std::string& command, const std::string& where,
                              std::vector<Event>* out) {
  for (const auto& [text, at] : body_) {
    if (text.size() < 2) {
      ++counters_.checksum_errors;
      out->push_back(DecodeError{at, where + ": line too short for its checksum"});
      return false;
    }
    const std::string_view data(text.data(), text.size() - 1);
    const bool info = command == "VV" || command == "PP" || command == "II";
    // Info lines: the checksum covers the characters before the ';'.
    const std::string_view summed =
        info && !data.empty() && data.back() == ';' ? data.substr(0, data.size() - 1) : data;
    if (checksum(summed) != text.back()) {
      ++counters_.checksum_errors;
      out->push_back(DecodeError{at, where + ": checksum '" + std::string(1, text.back()) +
                                         "' of a data line should be '" + checksum(summed) +
                                         "'; reply dropped"});
      return false;
    }
  }
  return true;
}

// A scan reply (GD/GS/GE, or a streamed MD/MS/ME scan): the echo's range, the time stamp
// line, then the values over the data lines.
void Decoder::emitScan(const std::string& command, const std::string& where,
                       std::vector<Event>* out) {
  ScanData s;
  s.command = command;
  s.offset = reply_offset_;
  s.start_step = digits(echo_, 2, 4);
  s.end_step = digits(echo_, 6, 4);
  s.cluster = std::max(1, digits(echo_, 10, 2));
  if (isStream(command)) s.remaining = std::max(0, digits(echo_, 13, 2));
  if (s.start_step < 0 || s.end_step < s.start_step || body_.empty() ||
      body_.front().first.size() != kStampChars + 1) {
    ++counters_.device_errors;
    out->push_back(DecodeError{reply_offset_, where + ": malformed scan header '" + echo_ + "'"});
    return;
  }
  s.time_ms = *decodeValue(std::string_view(body_.front().first).substr(0, kStampChars));
  if (!decodeScanValues(where, &s, out)) return;
  ++counters_.packets;
  ++counters_.scans;
  out->push_back(std::move(s));
}

// The data lines (their checksums off) joined and cut into one range (and intensity) per
// cluster of `s`'s steps.
bool Decoder::decodeScanValues(const std::string& where, ScanData* s, std::vector<Event>* out) {
  const std::string& command = s->command;
  std::string joined;
  for (size_t i = 1; i < body_.size(); ++i) {
    joined.append(body_[i].first, 0, body_[i].first.size() - 1);
  }
  const int per = charsPerValue(command) * (hasIntensity(command) ? 2 : 1);
  const size_t n = static_cast<size_t>((s->end_step - s->start_step) / s->cluster + 1);
  if (joined.size() != n * static_cast<size_t>(per)) {
    ++counters_.device_errors;
    out->push_back(DecodeError{reply_offset_, where + ": " + std::to_string(joined.size()) +
                                                  " data characters, expected " +
                                                  std::to_string(n * per)});
    return false;
  }
  const int w = charsPerValue(command);
  s->ranges_mm.resize(n);
  if (hasIntensity(command)) s->intensities.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const std::string_view v(joined.data() + i * per, static_cast<size_t>(per));
    const auto r = decodeValue(v.substr(0, static_cast<size_t>(w)));
    const auto in = hasIntensity(command) ? decodeValue(v.substr(static_cast<size_t>(w)))
                                          : std::optional<uint32_t>(0);
    if (!r || !in) {
      // A flipped bit 6 passes SCIP's 6-bit checksum; a character out of range shows it.
      ++counters_.checksum_errors;
      out->push_back(
          DecodeError{reply_offset_, where + ": invalid character in value " + std::to_string(i)});
      return false;
    }
    s->ranges_mm[i] = *r;
    if (hasIntensity(command)) s->intensities[i] = *in;
  }
  return true;
}

// Any other reply: its status, the KEY:value; lines of VV/PP/II, the time of TM1.
void Decoder::emitReply(const std::string& command, const std::string& where,
                        std::vector<Event>* out) {
  Reply r;
  r.command = command;
  r.echo = echo_;
  r.status = status_;
  r.offset = reply_offset_;
  r.ok = status_ == "00" || (command == "BM" && status_ == "02");
  if (command == "VV" || command == "PP" || command == "II") {
    for (const auto& [text, at] : body_) {
      const size_t colon = text.find(':');
      const size_t semi = text.rfind(';');
      if (colon == std::string::npos || semi == std::string::npos || semi < colon) {
        ++counters_.device_errors;
        out->push_back(DecodeError{at, where + ": '" + text + "' is not KEY:value;"});
        return;
      }
      r.params[text.substr(0, colon)] = text.substr(colon + 1, semi - colon - 1);
    }
  }
  if (command == "TM" && echo_.size() >= 3 && echo_[2] == '1' && status_ == "00") {
    if (body_.size() != 1 || body_[0].first.size() != kStampChars + 1) {
      ++counters_.device_errors;
      out->push_back(DecodeError{reply_offset_, where + ": TM1 without its time"});
      return;
    }
    r.time_ms = decodeValue(std::string_view(body_[0].first).substr(0, kStampChars));
  }
  if (!r.ok) ++counters_.device_errors;
  ++counters_.packets;
  out->push_back(std::move(r));
}

double Params::stepRad() const { return 2.0 * M_PI / ares; }
double Params::angleRad(double step) const { return (step - afrt) * stepRad(); }

Params parseParams(const std::map<std::string, std::string>& pp) {
  Params p;
  const auto number = [&](const char* key, int lo, int hi) {
    const auto it = pp.find(key);
    if (it == pp.end()) throw std::runtime_error(std::string("SCIP PP: no ") + key);
    // "SCAN:2400" or "DMAX:30000"; some firmware append units or text after a space.
    int v = 0;
    size_t i = 0;
    const std::string& s = it->second;
    if (s.empty() || !isDigit(s[0])) {
      throw std::runtime_error(std::string("SCIP PP: ") + key + " '" + s + "' is not a number");
    }
    for (; i < s.size() && isDigit(s[i]) && v < 100000000; ++i) v = v * 10 + (s[i] - '0');
    if (v < lo || v > hi) {
      throw std::runtime_error(std::string("SCIP PP: ") + key + " " + std::to_string(v) +
                               " outside " + std::to_string(lo) + ".." + std::to_string(hi));
    }
    return v;
  };
  const auto model = pp.find("MODL");
  p.model = model == pp.end() ? "" : model->second;
  p.dmin_mm = number("DMIN", 0, 100000);
  p.dmax_mm = number("DMAX", 1, 1000000);
  p.ares = number("ARES", 4, 100000);
  p.amin = number("AMIN", 0, 100000);
  p.amax = number("AMAX", 0, 100000);
  p.afrt = number("AFRT", 0, 100000);
  p.scan_rpm = number("SCAN", 1, 100000);
  if (p.amax < p.amin || p.amax >= p.ares + p.amin) {
    throw std::runtime_error("SCIP PP: AMIN " + std::to_string(p.amin) + " .. AMAX " +
                             std::to_string(p.amax) + " is not a range of steps");
  }
  if (p.dmax_mm <= p.dmin_mm) throw std::runtime_error("SCIP PP: DMAX not above DMIN");
  return p;
}

Scan2D toScan2D(const ScanData& scan, const Params& pp) {
  Scan2D s;
  const int c = std::max(1, scan.cluster);
  s.angle_min_rad = pp.angleRad(scan.start_step + 0.5 * (c - 1));
  s.angle_increment_rad = pp.stepRad() * c;
  const size_t n = scan.ranges_mm.size();
  const int last_steps = n == 0 ? c : scan.end_step - (scan.start_step + int(n - 1) * c) + 1;
  if (last_steps < c) {
    // The end step cuts the last cluster short: its middle is not on the grid.
    s.angles_rad.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const int first = scan.start_step + int(i) * c;
      const int steps = std::min(c, scan.end_step - first + 1);
      s.angles_rad[i] = static_cast<float>(pp.angleRad(first + 0.5 * (steps - 1)));
    }
  }
  s.range_min_m = pp.dmin_mm * 1e-3;
  s.range_max_m = pp.dmax_mm * 1e-3;
  s.device_stamp = scan.time_ms;
  s.ranges_m.resize(scan.ranges_mm.size());
  for (size_t i = 0; i < scan.ranges_mm.size(); ++i) {
    const uint32_t mm = scan.ranges_mm[i];
    s.ranges_m[i] =
        (mm < static_cast<uint32_t>(pp.dmin_mm) || mm > static_cast<uint32_t>(pp.dmax_mm))
            ? 0.0f
            : static_cast<float>(mm * 1e-3);
  }
  s.intensities.assign(scan.intensities.begin(), scan.intensities.end());
  return s;
}

double firstRayDelayS(const ScanData& scan, const Params& pp) {
  return (scan.start_step + 0.5 * (std::max(1, scan.cluster) - 1)) * pp.stepPeriodS();
}

std::string scanCommand(const std::string& command, int start, int end, int cluster, int skip,
                        int scans) {
  char buf[32];
  if (isStream(command)) {
    std::snprintf(buf, sizeof buf, "%s%04d%04d%02d%01d%02d\n", command.c_str(), start, end, cluster,
                  skip, scans);
  } else {
    std::snprintf(buf, sizeof buf, "%s%04d%04d%02d\n", command.c_str(), start, end, cluster);
  }
  return buf;
}

}  // namespace scip
}  // namespace sweepmap
