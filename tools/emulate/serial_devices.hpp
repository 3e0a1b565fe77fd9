// Emulated 360° serial lidars, each sample sent at its own time (a real device sends as it
// measures): a YDLIDAR X4 (drivers/protocols/ydlidar.hpp) and an RPLIDAR A1 in standard
// scan mode (drivers/protocols/rplidar.hpp). The source must hand out scans as they begin
// (their rays are known ahead: the simulated car's path is scripted); ray i of a scan is
// measured at rayUtime(i) in the direction rayAngle(i) (lidar frame L, the device angle).
//
// X4: identity model 6 (X4), firmware 1.5, hardware 1. Packets of 40 samples, some cut short
// (1 to 39, at random), sent when their last sample has been measured; the zero packet (CT bit
// 0, one sample) where the turn starts: the first sample after A5 60 wherever it is, then
// where the motor passes its index mark (348°), as a real X4 does; now and then a packet
// whose LSA lies below its FSA, off the 360 -> 0 wrap. As the hardware does, the X4 reports
// its motor angles (FSA, LSA: evenly stepped, as the motor turns evenly and samples at a
// steady rate: the scans' grid of rays), and the host adds AngCorrect(d) to each sample
// (X4 development manual); the triangulation geometry makes the beam look off the motor angle
// by just that, so the source must cast each ray along motor + AngCorrect(range)
// (beamOffsetRad, castBeam in sim/beam.hpp; Scan2D::angles_rad), and the host then puts
// every sample where it was measured.
// RPLIDAR A1: identity model 0x18 (A1M8), firmware 1.29, hardware 7; 5-byte samples, S = 1
// on the first sample of each turn (at the 0° mark), quality 47 for a return, 0 for none;
// RESET prints the A1's start-up banner. Neither device answers while it is scanning except
// to STOP (RPLIDAR also to RESET).
#pragma once

#include <deque>
#include <random>
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
    double angle_deg;  // device angle where the ray looked, [0, 360)
    double motor_deg;  // the motor's angle then, [0, 360): the scan's grid
    double distance_mm;
    bool turn_start;  // the first sample whose motor angle is at or past the 0° mark
  };
  // Samples measured by now_us, oldest first, each once.
  std::deque<Sample>& pending(int64_t now_us);
  void clear() { samples_.clear(); }
  void skipTo(int64_t now_us);  // drop what was measured before now (not sent)

 private:
  ScanSource source_;
  std::deque<Sample> samples_;
  double last_motor_ = -1.0;
};

class X4Device : public EmulatedLidar {
 public:
  // Where a real X4 puts its zero packets once turning (tests/data/real/README.md: 348.0 ..
  // 348.6 deg in three streams), the share of packets cut short (about 9 % there, 1 .. 39
  // samples) and of packets with LSA below FSA off the wrap (1 of 1949 there).
  static constexpr double kIndexMarkDeg = 348.0;
  static constexpr double kShortPacketShare = 0.09;
  static constexpr double kAnomalyShare = 1.0 / 2000.0;
  // Where the X4's beam looks off its motor angle [rad] for the range measured along it [m]
  // (the X4 development manual's AngCorrect; 0 without a return).
  static double beamOffsetRad(double range_m);
  explicit X4Device(ScanSource source, uint64_t seed = 22) : feed_(std::move(source)), rng_(seed) {}
  void receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) override;
  void advance(int64_t now_us, std::string* out) override;
  void reset(int64_t now_us) override;

 private:
  bool ringStart(const SampleFeed::Sample& s, double prev_motor) const;
  size_t packetLength(const std::deque<SampleFeed::Sample>& q, int64_t now_us);
  SampleFeed feed_;
  std::string command_;
  bool scanning_ = false;
  double last_sent_motor_ = -1.0;  // the last sample sent: its motor angle; < 0: none yet
  size_t target_ = 0;              // the packet being filled: its length, 0 = not chosen yet
  std::mt19937_64 rng_;
  bool last_full_ = false;  // the last packet sent had 40 samples
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
