// Emulated rig-B odometry devices on a serial line, fed by the simulated car
// (tools/emulate/world.hpp), each sample sent at its own time:
//  - Hi219Device: a HiPNUC HI219 streaming the 0x91 record (drivers/protocols/hi219.hpp) at the
//    rig's sim.imu_rate_hz, its time stamp the IMU's millisecond clock since power-up (plus
//    clock_offset_ms, times 1 + drift); it ignores the host's AT configuration commands (they
//    change nothing the emulation models);
//  - WheelBoardDevice: our wheel board (drivers/protocols/wheelboard.hpp): a TICKS frame at each
//    encoder reading (sim.wheel_ticks_rate_hz), its time the board's microsecond clock; SPEED
//    frames from the host are decoded and counted, and the board's watchdog flag is raised when
//    none has come for 0.5 s after the first. The car follows its scripted path: the commanded
//    speeds do not move it (documented in the README).
// A device powered up afresh (after a hang-up) sends nothing measured before it was on.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "devices/odometry_devices.hpp"
#include "drivers/protocols/wheelboard.hpp"
#include "tools/emulate/emulated_lidar.hpp"

namespace sweepmap {

using ImuSource = std::function<std::vector<ImuSample>(int64_t now_us)>;
using TicksSource = std::function<std::vector<WheelTicks>(int64_t now_us)>;

// A device's own clock: at true time t [us] after power-up at p it reads
// offset_us + (t - p)(1 + drift_ppm 1e-6) [us].
struct DeviceClockModel {
  double offset_us = 0.0;
  double drift_ppm = 0.0;
  int64_t at(int64_t power_on_us, int64_t t_us) const;
};

// What an emulated HI219 streams: the 0x91 record, or the old item set (0x90 A0 B0 C0 D0 F0)
// that the HI219 of Miao 2022's era sends by default (it has no time stamp).
enum class Hi219Frames { kImusol91, kOldItems };

class Hi219Device : public EmulatedLidar {
 public:
  Hi219Device(ImuSource source, const DeviceClockModel& clock, int64_t power_on_us,
              Hi219Frames frames = Hi219Frames::kImusol91);
  void receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) override {}
  void advance(int64_t now_us, std::string* out) override;
  void reset(int64_t now_us) override {}

 private:
  ImuSource source_;
  DeviceClockModel clock_;
  int64_t power_on_us_;
  Hi219Frames frames_;
};

class WheelBoardDevice : public EmulatedLidar {
 public:
  WheelBoardDevice(TicksSource source, const DeviceClockModel& clock, int64_t power_on_us);
  void receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) override;
  void advance(int64_t now_us, std::string* out) override;
  void reset(int64_t now_us) override {}
  int64_t speedFrames() const { return speed_frames_; }

 private:
  TicksSource source_;
  DeviceClockModel clock_;
  int64_t power_on_us_;
  uint16_t seq_ = 0;
  wheelboard::Decoder decoder_;
  std::vector<wheelboard::Event> events_;
  int64_t last_speed_us_ = -1;
  int64_t speed_frames_ = 0;
};

}  // namespace sweepmap
