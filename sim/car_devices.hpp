// The simulated rig-B car's devices behind the same interfaces as the real drivers: its IMU,
// its wheel board and its lidar, each handing out what the car's simulation
// (sim/mobile.hpp) produced for the whole run once its time has come (a scan when it
// is delivered, SimMobile::scanDeliveryUtime). Before the start and after the run
// (sim.duration_s) the car stands, and each device streams at its rate repeating its first or
// last output (a real one standing still reads about the same), so a process that opens it
// early or late finds it streaming. Same seed and start time → the same samples in every
// process (sweepmap-odometry --device sim and sweepmap-lidar --device sim share one car).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "devices/lidar_device.hpp"
#include "devices/odometry_devices.hpp"
#include "sim/mobile.hpp"

namespace sweepmap {

// Items (with a `utime`) in time order, handed out once their time is <= now. With a
// hold period, a powered device at rest: before the first item is due, copies of the first on
// its grid (due - k * hold_period_us, from the first take() on); after the last, copies of the
// last every hold_period_us, for ever (utime shifted by as much).
template <class T>
class TimedFeed {
 public:
  TimedFeed() = default;
  TimedFeed(std::vector<T> items, std::vector<int64_t> due, int64_t hold_period_us)
      : items_(std::move(items)), due_(std::move(due)), hold_period_us_(hold_period_us) {}
  std::vector<T> take(int64_t now_utime) {
    std::vector<T> out;
    if (items_.empty()) return out;
    if (hold_period_us_ > 0 && next_ == 0) {
      if (!lead_started_) {
        lead_started_ = true;
        lead_due_ =
            now_utime >= due_.front()
                ? due_.front()
                : due_.front() - (due_.front() - now_utime) / hold_period_us_ * hold_period_us_;
      }
      for (; lead_due_ < due_.front() && lead_due_ <= now_utime; lead_due_ += hold_period_us_) {
        T copy = items_.front();
        copy.utime += lead_due_ - due_.front();
        out.push_back(copy);
      }
    }
    while (next_ < items_.size() && due_[next_] <= now_utime) out.push_back(items_[next_++]);
    if (next_ < items_.size() || hold_period_us_ <= 0) return out;
    while (due_.back() + hold_period_us_ <= now_utime) {
      due_.back() += hold_period_us_;
      items_.back().utime += hold_period_us_;
      out.push_back(items_.back());
    }
    return out;
  }

 private:
  std::vector<T> items_;
  std::vector<int64_t> due_;
  int64_t hold_period_us_ = 0;
  size_t next_ = 0;
  bool lead_started_ = false;
  int64_t lead_due_ = 0;
};

class SimImu : public ImuDevice {
 public:
  explicit SimImu(SimMobile* car);
  std::vector<ImuSample> poll(int64_t now_utime) override { return feed_.take(now_utime); }

 private:
  TimedFeed<ImuSample> feed_;
};

class SimWheels : public WheelDevice {
 public:
  explicit SimWheels(SimMobile* car);
  std::vector<WheelTicks> poll(int64_t now_utime) override { return feed_.take(now_utime); }

 private:
  TimedFeed<WheelTicks> feed_;
};

class SimCarLidar : public LidarDevice {
 public:
  explicit SimCarLidar(SimMobile* car);
  std::vector<Scan2D> poll(int64_t now_utime) override { return feed_.take(now_utime); }

 private:
  TimedFeed<Scan2D> feed_;
};

// The car's true pose (TRUTH_POSE) at sim.truth_rate_hz.
class SimCarTruth {
 public:
  explicit SimCarTruth(const SimMobile& car);
  std::vector<TruthPose> poll(int64_t now_utime) { return feed_.take(now_utime); }

 private:
  TimedFeed<TruthPose> feed_;
};

}  // namespace sweepmap
