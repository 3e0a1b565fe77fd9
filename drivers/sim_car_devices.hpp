// The simulated rig-B car's devices behind the same interfaces as the real drivers: its IMU,
// its wheel board and its lidar, each handing out what the car's simulation
// (drivers/sim_mobile.hpp) produced for the whole run once its time has come (a scan when it
// is delivered, SimMobile::scanDeliveryUtime). The run ends at sim.duration_s: then the car
// stands, and each device goes on at its rate repeating its last output (a real one standing
// still reads about the same). Same seed and start time → the same samples in every
// process (sweepmap-odometry --device sim and sweepmap-lidar --device sim share one car).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "drivers/lidar_device.hpp"
#include "drivers/odometry_devices.hpp"
#include "drivers/sim_mobile.hpp"

namespace sweepmap {

// Items (with a `utime`) in time order, handed out once their time is <= now; after the last,
// copies of it every `hold_period_us` (utime advanced by as much), for ever.
template <class T>
class TimedFeed {
 public:
  TimedFeed() = default;
  TimedFeed(std::vector<T> items, std::vector<int64_t> due, int64_t hold_period_us)
      : items_(std::move(items)), due_(std::move(due)), hold_period_us_(hold_period_us) {}
  std::vector<T> take(int64_t now_utime) {
    std::vector<T> out;
    while (next_ < items_.size() && due_[next_] <= now_utime) out.push_back(items_[next_++]);
    if (next_ < items_.size() || items_.empty() || hold_period_us_ <= 0) return out;
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
