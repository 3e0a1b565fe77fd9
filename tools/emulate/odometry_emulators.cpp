#include "tools/emulate/odometry_emulators.hpp"

#include <cmath>

#include "drivers/protocols/hi219.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kWatchdogUs = 500000;

}  // namespace

int64_t DeviceClockModel::at(int64_t power_on_us, int64_t t_us) const {
  return static_cast<int64_t>(
      std::floor(offset_us + static_cast<double>(t_us - power_on_us) * (1.0 + drift_ppm * 1e-6)));
}

Hi219Device::Hi219Device(ImuSource source, const DeviceClockModel& clock, int64_t power_on_us,
                         Hi219Frames frames)
    : source_(std::move(source)), clock_(clock), power_on_us_(power_on_us), frames_(frames) {}

void Hi219Device::advance(int64_t now_us, std::string* out) {
  for (const ImuSample& s : source_(now_us)) {
    if (s.utime < power_on_us_) continue;  // measured while the IMU was off
    hi219::Frame f;
    f.id = 0;
    f.time_ms = static_cast<uint32_t>(clock_.at(power_on_us_, s.utime) / 1000);
    for (int k = 0; k < 3; ++k) {
      f.accel_m_s2[k] = s.accel[k];
      f.gyro_rad_s[k] = s.gyro[k];
      f.rpy_rad[k] = s.rpy[k];
    }
    // The attitude as a quaternion (w, x, y, z) from roll, pitch, yaw (Z-Y-X).
    const double cr = std::cos(s.rpy[0] / 2), sr = std::sin(s.rpy[0] / 2);
    const double cp = std::cos(s.rpy[1] / 2), sp = std::sin(s.rpy[1] / 2);
    const double cy = std::cos(s.rpy[2] / 2), sy = std::sin(s.rpy[2] / 2);
    f.quat_wxyz = {cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                   cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy};
    f.pressure_pa = 101325.0;
    *out += hi219::encodeFrame(frames_ == Hi219Frames::kOldItems ? hi219::encodeOldItems(f)
                                                                 : hi219::encodeImusol(f));
  }
}

WheelBoardDevice::WheelBoardDevice(TicksSource source, const DeviceClockModel& clock,
                                   int64_t power_on_us)
    : source_(std::move(source)), clock_(clock), power_on_us_(power_on_us) {}

void WheelBoardDevice::receive(const uint8_t* data, size_t size, int64_t now_us, std::string*) {
  events_.clear();
  decoder_.feed(data, size, &events_);
  for (const auto& e : events_) {
    if (std::holds_alternative<wheelboard::Speed>(e)) {
      last_speed_us_ = now_us;
      ++speed_frames_;
    }
  }
}

void WheelBoardDevice::advance(int64_t now_us, std::string* out) {
  for (const WheelTicks& t : source_(now_us)) {
    if (t.utime < power_on_us_) continue;  // read while the board was off
    wheelboard::Ticks f;
    f.seq = seq_++;
    f.time_us = static_cast<uint32_t>(static_cast<uint64_t>(clock_.at(power_on_us_, t.utime)));
    f.left = static_cast<int32_t>(static_cast<uint32_t>(static_cast<uint64_t>(t.left)));
    f.right = static_cast<int32_t>(static_cast<uint32_t>(static_cast<uint64_t>(t.right)));
    if (last_speed_us_ >= 0 && t.utime - last_speed_us_ > kWatchdogUs) {
      f.flags |= wheelboard::kFlagWatchdog;
    }
    *out += wheelboard::encodeTicks(f);
  }
}

}  // namespace sweepmap
