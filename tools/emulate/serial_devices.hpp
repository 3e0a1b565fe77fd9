// Emulated 360° serial lidars, each sample sent at its own time (a real device sends as it
// measures): a YDLIDAR X4 (drivers/protocols/ydlidar.hpp) and an RPLIDAR A1 in standard
// scan mode (drivers/protocols/rplidar.hpp). The source must hand out scans as they begin
// (their rays are known ahead: the simulated car's path is scripted); ray i of a scan is
// measured at rayUtime(i) in the direction rayAngle(i) (lidar frame L, the device angle).
//
// X4: identity model 6 (X4), firmware 1.5, hardware 1. Packets of at most 40 samples, sent
// when their last sample has been measured; the zero packet (CT bit 0, one sample) where a
// turn passes the 0° mark. The X4 reports mirror (raw) angles: raw = true - AngCorrect(d);
// the host interpolates raw angles linearly inside a packet, so a packet is closed early
// where that interpolation would be off by more than 0.01° for one of its samples.
// RPLIDAR A1: identity model 0x18 (A1M8), firmware 1.29, hardware 7; 5-byte samples, S = 1
// on the first sample of each turn (at the 0° mark), quality 47 for a return, 0 for none;
// RESET prints the A1's start-up banner. Neither device answers while it is scanning except
// to STOP (RPLIDAR also to RESET).
#pragma once

#include <deque>
#include <string>

#include "drivers/protocols/rplidar.hpp"
#include "tools/emulate/emulated_lidar.hpp"

namespace sweepmap {

// Samples of the source's scans in time order, as device angles [0, 360) deg.
class SampleFeed {
 public:
  explicit SampleFeed(ScanSource source) : source_(std::move(source)) {}
  struct Sample {
    int64_t utime;
    double angle_deg;  // device angle, [0, 360)
    double distance_mm;
    bool turn_start;  // the first sample at or past the 0° mark
  };
  // Samples measured by now_us, oldest first, each once.
  std::deque<Sample>& pending(int64_t now_us);
  void clear() { samples_.clear(); }
  void skipTo(int64_t now_us);  // drop what was measured before now (not sent)

 private:
  ScanSource source_;
  std::deque<Sample> samples_;
  double last_angle_ = -1.0;
};

class X4Device : public EmulatedLidar {
 public:
  explicit X4Device(ScanSource source) : feed_(std::move(source)) {}
  void receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) override;
  void advance(int64_t now_us, std::string* out) override;
  void reset(int64_t now_us) override;

 private:
  SampleFeed feed_;
  std::string command_;
  bool scanning_ = false;
};

class RplidarDevice : public EmulatedLidar {
 public:
  explicit RplidarDevice(ScanSource source) : feed_(std::move(source)) {}
  void receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) override;
  void advance(int64_t now_us, std::string* out) override;
  void reset(int64_t now_us) override;

 private:
  SampleFeed feed_;
  rplidar::RequestParser parser_;
  bool scanning_ = false;
};

}  // namespace sweepmap
