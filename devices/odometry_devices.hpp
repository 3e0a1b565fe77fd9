// Rig B's odometry devices as sweepmap-odometry sees them, real (drivers/odometry_drivers.hpp)
// or simulated (sim/car_devices.hpp): the IMU and the wheel board.
#pragma once

#include <cstdint>
#include <vector>

#include "devices/lidar_device.hpp"

namespace sweepmap {

// One IMU sample, IMU axes (x forward, y left, z up on rig B), SI units.
struct ImuSample {
  int64_t utime;
  double gyro[3], accel[3], rpy[3];  // rad/s, m/s^2, rad (NaN: the IMU gave no attitude)
};

// One encoder reading: cumulative counts (unwrapped), the board's status flags.
struct WheelTicks {
  int64_t utime;
  int64_t left, right;
  uint16_t flags = 0;  // wheelboard::kFlag*; 0 for a simulated board
};

class ImuDevice {
 public:
  virtual ~ImuDevice() = default;
  // Samples delivered up to `now_utime`, in time order, each once.
  virtual std::vector<ImuSample> poll(int64_t now_utime) = 0;
  virtual DeviceHealth health() { return {}; }
  // Whether samples are arriving (a real device: between a start-up and the connection's end).
  virtual bool streaming() const { return true; }
};

class WheelDevice {
 public:
  virtual ~WheelDevice() = default;
  virtual std::vector<WheelTicks> poll(int64_t now_utime) = 0;
  // A speed command (WHEEL_CMD), sent to the board at once. A simulated car ignores it (it
  // drives its scripted path).
  virtual void command(int64_t now_utime, double v_m_s, double w_rad_s) {}
  virtual DeviceHealth health() { return {}; }
  virtual bool streaming() const { return true; }
};

}  // namespace sweepmap
