#include "tools/emulate/scip_device.hpp"

#include <cmath>

#include "drivers/protocols/scip.hpp"

namespace sweepmap {
namespace {

bool allDigits(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

std::string infoLine(const std::string& key_value) {
  // The checksum covers the characters before the ';'.
  return key_value + ";" + scip::checksum(key_value) + "\n";
}

// Data split into 64-character blocks, each with its checksum and a line end.
std::string blocks(const std::string& data) {
  std::string out;
  for (size_t at = 0; at < data.size(); at += 64) {
    const std::string b = data.substr(at, 64);
    out += b;
    out.push_back(scip::checksum(b));
    out.push_back('\n');
  }
  return out;
}

}  // namespace

namespace {
LidarModel scipModel(const std::string& name) {
  const LidarModel* m = findLidarModel(name);
  if (m == nullptr || m->protocol != DeviceProtocol::kScip) {
    throw std::invalid_argument("no SCIP lidar model '" + name + "'");
  }
  return *m;
}
}  // namespace

ScipDevice::ScipDevice(ScanSource source, const EmulatedClock& clock, int64_t power_on_us,
                       const std::string& model)
    : source_(std::move(source)),
      model_(scipModel(model)),
      clock_(clock),
      power_on_us_(power_on_us) {}

uint32_t ScipDevice::counterAt(int64_t t_us) const {
  return static_cast<uint32_t>(clock_.counterAt(power_on_us_, t_us));
}

void ScipDevice::reset(int64_t now_us) {
  line_.clear();
  laser_on_ = false;
  adjust_mode_ = false;
  streaming_ = false;
}

void ScipDevice::receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) {
  for (size_t i = 0; i < size; ++i) {
    const char c = static_cast<char>(data[i]);
    if (c == '\n' || c == '\r') {
      // CR, LF or CR LF end a command; an empty line is nothing.
      if (!line_.empty()) command(line_, now_us, out);
      line_.clear();
      continue;
    }
    if (line_.size() < 256) line_.push_back(c);
  }
}

namespace {

// The tag after a ';' (at most 16 printable characters) taken off `params`; the error status
// of a bad tag, or "" when there is none or it is good.
std::string splitTag(std::string* params, std::string* tag) {
  const size_t semi = params->find(';');
  if (semi == std::string::npos) return "";
  *tag = params->substr(semi + 1);
  params->resize(semi);
  if (tag->size() > 16) return "0G";
  for (char c : *tag) {
    if (c < 0x20 || c > 0x7e) return "0H";
  }
  return "";
}

}  // namespace

void ScipDevice::command(const std::string& line, int64_t now_us, std::string* out) {
  const auto reply = [&](const std::string& status, const std::string& body = "") {
    *out += line + "\n" + scip::withChecksum(status) + "\n" + body + "\n";
  };
  if (line.size() < 2) return reply("0C");
  const std::string cmd = line.substr(0, 2);
  std::string params = line.substr(2), tag;
  if (const std::string bad_tag = splitTag(&params, &tag); !bad_tag.empty()) return reply(bad_tag);
  if (cmd == "VV" || cmd == "PP" || cmd == "II") {
    if (!params.empty()) return reply("0C");
    return reply("00", identityBody(cmd, now_us));
  }
  if (cmd == "BM" || cmd == "QT" || cmd == "RS" || cmd == "RT") return reply(laserCommand(cmd));
  if (cmd == "TM") {
    const Reply r = timeAdjustCommand(params, now_us);
    return reply(r.status, r.body);
  }
  const bool stream = cmd == "MD" || cmd == "MS" || cmd == "ME";
  const bool single = cmd == "GD" || cmd == "GS" || cmd == "GE";
  if (!stream && !single) return reply("0E");
  if ((cmd == "ME" || cmd == "GE") && !model_.scip_intensity) return reply("0E");  // URG-04LX
  Request request{cmd, 0, 0, 1};
  if (const std::string bad = parseRange(params, stream, &request); !bad.empty()) return reply(bad);
  if (single) {
    if (!laser_on_) return reply("10");
    if (!latest_) return reply("0B");  // nothing measured yet: busy
    *out += line + "\n" + scip::withChecksum("00") + "\n";
    return scanReply(*latest_, request, "", out);
  }
  const std::string s_skip = params.substr(10, 1), s_count = params.substr(11, 2);
  if (!allDigits(s_skip)) return reply("06");
  if (!allDigits(s_count)) return reply("07");
  reply("00");
  startStream(request, std::stoi(s_skip), std::stoi(s_count), tag);
}

std::string ScipDevice::identityBody(const std::string& cmd, int64_t now_us) const {
  const ScipGeometry& pp = model_.pp;
  const std::string& name = model_.name;
  if (cmd == "VV") {
    return infoLine("VEND:Hokuyo Automatic Co.,Ltd.") + infoLine("PROD:SOKUIKI Sensor " + name) +
           infoLine("FIRM:1.1.3(2016-03-02)") + infoLine("PROT:SCIP 2.0") +
           infoLine("SERI:H1612345");
  }
  if (cmd == "PP") {
    const auto key = [](const char* k, int v) { return infoLine(k + std::to_string(v)); };
    return infoLine("MODL:" + name + "(Hokuyo Automatic Co.,Ltd.)") + key("DMIN:", pp.dmin_mm) +
           key("DMAX:", pp.dmax_mm) + key("ARES:", pp.ares) + key("AMIN:", pp.amin) +
           key("AMAX:", pp.amax) + key("AFRT:", pp.afrt) + key("SCAN:", pp.scan_rpm);
  }
  char time[16];
  std::snprintf(time, sizeof time, "%06X", counterAt(now_us));
  return infoLine("MODL:" + name) + infoLine(std::string("LASR:") + (laser_on_ ? "ON" : "OFF")) +
         infoLine("SCSP:Initial(" + std::to_string(pp.scan_rpm) + "[rpm])") +
         infoLine("MESM:Measuring by Normal Mode") + infoLine("SBPS:Ethernet 100 [Mbps]") +
         infoLine(std::string("TIME:") + time) + infoLine("STAT:Stable 000 no error.");
}

std::string ScipDevice::laserCommand(const std::string& cmd) {
  if (cmd == "BM") {
    const bool was_on = laser_on_;
    laser_on_ = true;
    return was_on ? "02" : "00";
  }
  streaming_ = false;
  laser_on_ = false;
  if (cmd == "RS" || cmd == "RT") adjust_mode_ = false;  // QT keeps the time adjust mode
  return "00";
}

ScipDevice::Reply ScipDevice::timeAdjustCommand(const std::string& params, int64_t now_us) {
  if (params.size() != 1 || params[0] < '0' || params[0] > '2') return {"01", ""};
  if (params[0] == '0') {
    if (adjust_mode_) return {"02", ""};
    streaming_ = false;  // no measurement while the time is being adjusted
    adjust_mode_ = true;
    return {"00", ""};
  }
  if (!adjust_mode_) return {"03", ""};
  if (params[0] == '1') {
    return {"00", scip::withChecksum(scip::encodeValue(counterAt(now_us), 4)) + "\n"};
  }
  adjust_mode_ = false;
  return {"00", ""};
}

std::string ScipDevice::parseRange(const std::string& params, bool stream, Request* r) const {
  const size_t need = stream ? 13 : 10;
  if (params.size() < need) return "0C";
  if (params.size() > need) return "0F";
  const std::string s_start = params.substr(0, 4), s_end = params.substr(4, 4),
                    s_cluster = params.substr(8, 2);
  if (!allDigits(s_start)) return "01";
  if (!allDigits(s_end)) return "02";
  if (!allDigits(s_cluster)) return "03";
  r->start = std::stoi(s_start);
  r->end = std::stoi(s_end);
  r->cluster = std::max(1, std::stoi(s_cluster));
  if (r->start < model_.pp.amin || r->start > model_.pp.amax || r->end > model_.pp.amax) {
    return "04";
  }
  if (r->end < r->start) return "05";
  if (adjust_mode_) return "0B";
  return "";
}

void ScipDevice::startStream(const Request& r, int skip, int count, const std::string& tag) {
  streaming_ = true;
  laser_on_ = true;  // MD/MS/ME switch the laser on
  stream_command_ = r.command;
  stream_tag_ = tag;
  start_ = r.start;
  end_ = r.end;
  cluster_ = r.cluster;
  skip_ = skip;
  remaining_ = count;
  unlimited_ = remaining_ == 0;
  skipped_ = 0;
}

void ScipDevice::advance(int64_t now_us, std::string* out) {
  for (Scan2D& scan : source_(now_us)) {
    latest_ = std::move(scan);
    if (!streaming_) continue;
    if (skipped_ < skip_) {
      ++skipped_;
      continue;
    }
    skipped_ = 0;
    if (!unlimited_) --remaining_;
    char echo[32];
    std::snprintf(echo, sizeof echo, "%s%04d%04d%02d%01d%02d", stream_command_.c_str(), start_,
                  end_, cluster_, skip_, unlimited_ ? 0 : std::max(0, remaining_));
    const std::string head = std::string(echo) + (stream_tag_.empty() ? "" : ";" + stream_tag_) +
                             "\n" + scip::withChecksum("99") + "\n";
    scanReply(*latest_, Request{stream_command_, start_, end_, cluster_}, head, out);
    if (!unlimited_ && remaining_ <= 0) streaming_ = false;
  }
}

int64_t ScipDevice::stepUtime(const Scan2D& scan, double step) const {
  if (!(scan.angle_increment_rad > 0)) return scan.utime;
  const double rays = (model_.pp.angleRad(step) - scan.angle_min_rad) / scan.angle_increment_rad;
  return scan.utime + static_cast<int64_t>(std::llround(rays * scan.time_increment_ns * 1e-3));
}

int ScipDevice::rayAt(const Scan2D& scan, int step) const {
  if (!(scan.angle_increment_rad > 0)) return -1;
  const double rays = (model_.pp.angleRad(step) - scan.angle_min_rad) / scan.angle_increment_rad;
  const long i = std::lround(rays);
  if (std::fabs(rays - double(i)) > 0.01 || i < 0 || i >= long(scan.ranges_m.size())) return -1;
  return static_cast<int>(i);
}

// The values of `r`'s clusters, encoded.
std::string ScipDevice::dataOf(const Scan2D& scan, const Request& r) const {
  const bool intensity = r.command == "ME" || r.command == "GE";
  const int chars = (r.command == "MS" || r.command == "GS") ? 2 : 3;
  const auto dmin = static_cast<uint32_t>(model_.pp.dmin_mm);
  const auto dmax = static_cast<uint32_t>(model_.pp.dmax_mm);
  std::string data;
  for (int step = r.start; step <= r.end; step += r.cluster) {
    // A cluster reports its nearest valid range (the sensor's documented grouping rule).
    float r_best = 0.0f;
    for (int k = step; k < std::min(step + r.cluster, r.end + 1); ++k) {
      const int i = rayAt(scan, k);
      const float range = i >= 0 ? scan.ranges_m[static_cast<size_t>(i)] : 0.0f;
      if (range > 0.0f && (r_best == 0.0f || range < r_best)) r_best = range;
    }
    uint32_t mm = r_best > 0.0f ? static_cast<uint32_t>(std::lround(r_best * 1000.0)) : 0;
    const bool valid = mm >= dmin && mm <= dmax;
    if (!valid) mm = model_.no_return_code;
    data += scip::encodeValue(mm, chars);
    if (intensity) {
      const uint32_t in = valid ? static_cast<uint32_t>(std::lround(20000.0 / (1.0 + r_best))) : 0;
      data += scip::encodeValue(in, chars);
    }
  }
  return data;
}

void ScipDevice::scanReply(const Scan2D& scan, const Request& r, const std::string& head,
                           std::string* out) {
  *out += head;
  // The stamp: the counter at the scan's step 0 (SCIP2.0 specification, section 7).
  *out += scip::withChecksum(scip::encodeValue(counterAt(stepUtime(scan, 0)), 4)) + "\n";
  *out += blocks(dataOf(scan, r)) + "\n";
}

}  // namespace sweepmap
