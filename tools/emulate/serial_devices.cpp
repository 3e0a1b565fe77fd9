#include "tools/emulate/serial_devices.hpp"

#include <cmath>
#include <vector>

#include "drivers/protocols/ydlidar.hpp"

namespace sweepmap {
namespace {

double wrap360(double deg) {
  double d = std::fmod(deg, 360.0);
  return d < 0 ? d + 360.0 : d;
}

}  // namespace

std::deque<SampleFeed::Sample>& SampleFeed::pending(int64_t now_us) {
  // Fetch scans that have begun; their samples wait here until measured.
  const int64_t horizon = samples_.empty() ? now_us : samples_.back().utime;
  if (samples_.empty() || horizon <= now_us + 1000) {
    for (const Scan2D& scan : source_(now_us)) {
      for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
        const double a = wrap360(scan.rayAngle(i) * 180.0 / M_PI);
        const bool start = last_angle_ >= 0.0 && a < last_angle_ - 180.0;
        last_angle_ = a;
        samples_.push_back({scan.rayUtime(i), a, scan.ranges_m[i] * 1000.0, start});
      }
    }
  }
  return samples_;
}

void SampleFeed::skipTo(int64_t now_us) {
  pending(now_us);
  while (!samples_.empty() && samples_.front().utime < now_us) samples_.pop_front();
}

// ---- X4 ----------------------------------------------------------------------------------

void X4Device::reset(int64_t now_us) {
  scanning_ = false;
  command_.clear();
}

void X4Device::receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) {
  for (size_t i = 0; i < size; ++i) {
    command_.push_back(static_cast<char>(data[i]));
    if (command_.size() == 1 && static_cast<uint8_t>(command_[0]) != 0xA5) {
      command_.clear();
      continue;
    }
    if (command_.size() < 2) continue;
    const auto cmd = static_cast<uint8_t>(command_[1]);
    command_.clear();
    if (cmd == ydlidar::kCmdStop || cmd == ydlidar::kCmdRestart) {
      scanning_ = false;  // no reply
    } else if (scanning_) {
      continue;  // ignores everything else while scanning
    } else if (cmd == ydlidar::kCmdStart) {
      *out += ydlidar::encodeDescriptor(5, 1, ydlidar::kTypeScan);
      feed_.skipTo(now_us);
      scanning_ = true;
    } else if (cmd == ydlidar::kCmdInfo) {
      *out += ydlidar::encodeInfo(ydlidar::kModelX4, 1, 5, 1, "2019031200000042");
    } else if (cmd == ydlidar::kCmdHealth) {
      *out += ydlidar::encodeHealth(0, 0);
    }
  }
}

void X4Device::advance(int64_t now_us, std::string* out) {
  std::deque<SampleFeed::Sample>& q = feed_.pending(now_us);
  if (!scanning_) {
    while (!q.empty() && q.front().utime <= now_us) q.pop_front();
    return;
  }
  const auto raw = [](const SampleFeed::Sample& s) {
    return s.distance_mm > 0 ? s.angle_deg - ydlidar::angleCorrectionDeg(s.distance_mm)
                             : s.angle_deg;
  };
  for (;;) {
    if (q.empty() || q.front().utime > now_us) return;
    if (q.front().turn_start) {
      // The zero packet: one sample, at the 0° mark.
      const auto& s = q.front();
      *out += ydlidar::encodePacket(true, raw(s), raw(s), {s.distance_mm});
      q.pop_front();
      continue;
    }
    // Grow the packet while its samples are measured, it has < 40, no turn starts, and a
    // linear interpolation of the raw angles stays within 0.01° of each one.
    size_t n = 1;
    while (n < q.size() && n < 40 && q[n].utime <= now_us && !q[n].turn_start) {
      const double first = raw(q[0]);
      double span = raw(q[n]) - first;
      span -= 360.0 * std::round(span / 360.0);
      bool linear = true;
      for (size_t i = 1; i < n && linear; ++i) {
        double d = raw(q[i]) - first;
        d -= 360.0 * std::round(d / 360.0);
        linear = std::fabs(d - span * double(i) / double(n)) <= 0.01;
      }
      if (!linear) break;
      ++n;
    }
    // Wait for a fuller packet unless its first sample is 8 ms old.
    if (n < 40 && n == q.size() && now_us - q[0].utime < 8000) return;
    std::vector<double> d(n);
    for (size_t i = 0; i < n; ++i) d[i] = q[i].distance_mm;
    *out += ydlidar::encodePacket(false, raw(q[0]), raw(q[n - 1]), d);
    for (size_t i = 0; i < n; ++i) q.pop_front();
  }
}

// ---- RPLIDAR A1 ----------------------------------------------------------------------------

void RplidarDevice::reset(int64_t now_us) { scanning_ = false; }

void RplidarDevice::receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) {
  std::vector<rplidar::Request> requests;
  parser_.feed(data, size, &requests);
  for (const rplidar::Request& r : requests) {
    if (r.cmd == rplidar::kCmdStop) {
      scanning_ = false;
    } else if (r.cmd == rplidar::kCmdReset) {
      scanning_ = false;
      *out += "RP LIDAR System.\r\nFirmware Ver 1.29 - rc0, HW Ver 7\r\nModel: 18\r\n";
    } else if (scanning_ || r.cmd == rplidar::kCmdMotorPwm) {
      continue;
    } else if (r.cmd == rplidar::kCmdScan || r.cmd == rplidar::kCmdForceScan) {
      *out += rplidar::encodeDescriptor(5, 1, rplidar::kTypeScan);
      feed_.skipTo(now_us);
      scanning_ = true;
    } else if (r.cmd == rplidar::kCmdInfo) {
      *out += rplidar::encodeInfo(
          0x18, 1, 29, 7, "\x8c\x4b\x9a\xf0\xc4\xe2\x9b\xd4\xa0\xe5\x9e\xf2\x3f\x3a\x44\x1b");
    } else if (r.cmd == rplidar::kCmdHealth) {
      *out += rplidar::encodeHealth(0, 0);
    } else if (r.cmd == rplidar::kCmdSampleRate) {
      *out += rplidar::encodeDescriptor(4, 0, rplidar::kTypeSampleRate);
      *out += std::string("\xF4\x01\xFA\x00", 4);  // 500 us standard, 250 us express
    }
  }
}

void RplidarDevice::advance(int64_t now_us, std::string* out) {
  std::deque<SampleFeed::Sample>& q = feed_.pending(now_us);
  while (!q.empty() && q.front().utime <= now_us) {
    const auto& s = q.front();
    if (scanning_) {
      *out += rplidar::encodeSample(s.turn_start, s.distance_mm > 0 ? 47 : 0, s.angle_deg,
                                    s.distance_mm);
    }
    q.pop_front();
  }
}

}  // namespace sweepmap
