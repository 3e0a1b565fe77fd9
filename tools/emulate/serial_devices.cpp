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
        const double motor =
            wrap360((scan.angle_min_rad + scan.angle_increment_rad * double(i)) * 180.0 / M_PI);
        const bool start = last_motor_ >= 0.0 && motor < last_motor_ - 180.0;
        last_motor_ = motor;
        samples_.push_back({scan.rayUtime(i), wrap360(scan.rayAngle(i) * 180.0 / M_PI), motor,
                            scan.ranges_m[i] * 1000.0, start});
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

double X4Device::beamOffsetRad(double range_m) {
  return ydlidar::angleCorrectionDeg(range_m * 1000.0) * M_PI / 180.0;
}

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
      last_sent_motor_ = -1.0;
      target_ = 0;
    } else if (cmd == ydlidar::kCmdInfo) {
      *out += ydlidar::encodeInfo(ydlidar::kModelX4, 1, 5, 1, "2019031200000042");
    } else if (cmd == ydlidar::kCmdHealth) {
      *out += ydlidar::encodeHealth(0, 0);
    }
  }
}

// Whether `s`, coming after a sample at motor angle `prev_motor` (< 0: none since A5 60),
// starts a turn: the first sample after A5 60 does, then each one whose motor angle passes the
// index mark. As on a real X4, the first turn is a part of one (tests/data/real/README.md:
// scan3's first zero packet at 227.5°, the next at 348.0° 236 samples later).
bool X4Device::ringStart(const SampleFeed::Sample& s, double prev_motor) const {
  if (prev_motor < 0.0) return true;
  const double step = std::fmod(s.motor_deg - prev_motor + 360.0, 360.0);
  const double to_mark = std::fmod(kIndexMarkDeg - prev_motor + 360.0, 360.0);
  return to_mark > 0.0 && to_mark <= step;
}

// How many of the measured samples at the front of `q` the next packet takes (0: wait): up to
// its chosen length, while its samples are measured and no turn starts.
size_t X4Device::packetLength(const std::deque<SampleFeed::Sample>& q, int64_t now_us) {
  if (target_ == 0) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    target_ = u(rng_) < kShortPacketShare ? std::uniform_int_distribution<size_t>(1, 39)(rng_) : 40;
  }
  size_t n = 1;
  while (n < q.size() && n < target_ && q[n].utime <= now_us &&
         !ringStart(q[n], q[n - 1].motor_deg)) {
    ++n;
  }
  // Wait while the packet can still grow: its next sample not measured yet (the source hands
  // samples out ahead of their time), unless its first is 10 ms old.
  const bool can_grow = n < target_ && (n == q.size() || q[n].utime > now_us);
  if (can_grow && now_us - q[0].utime < 10000) return 0;
  return n;
}

void X4Device::advance(int64_t now_us, std::string* out) {
  std::deque<SampleFeed::Sample>& q = feed_.pending(now_us);
  if (!scanning_) {
    while (!q.empty() && q.front().utime <= now_us) q.pop_front();
    return;
  }
  for (;;) {
    if (q.empty() || q.front().utime > now_us) return;
    if (ringStart(q.front(), last_sent_motor_)) {
      // The zero packet: one sample, where the turn starts.
      const auto& s = q.front();
      *out += ydlidar::encodePacket(true, s.motor_deg, s.motor_deg, {s.distance_mm});
      last_full_ = false;
      last_sent_motor_ = s.motor_deg;
      q.pop_front();
      continue;
    }
    const size_t n = packetLength(q, now_us);
    if (n == 0) return;
    std::vector<double> d(n);
    for (size_t i = 0; i < n; ++i) d[i] = q[i].distance_mm;
    const double first = q[0].motor_deg;
    double last = q[n - 1].motor_deg;
    // Now and then a packet whose LSA lies just below its FSA, as a real X4 sends
    // (tests/data/real/README.md): the host keeps the previous packet's step.
    std::uniform_real_distribution<double> u(0.0, 1.0);
    // Only after a full packet: the host then reuses a step measured over 39 intervals, as
    // after the real capture's; after a zero or short packet it would have no usable step.
    if (last_full_ && n > 1 && first > 2.0 && first < 270.0 && u(rng_) < kAnomalyShare) {
      last = first - 1.171875;
    }
    *out += ydlidar::encodePacket(false, first, last, d);
    last_full_ = n == 40;
    last_sent_motor_ = q[n - 1].motor_deg;
    q.erase(q.begin(), q.begin() + static_cast<std::ptrdiff_t>(n));
    target_ = 0;
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
