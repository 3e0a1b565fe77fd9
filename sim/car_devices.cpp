#include "sim/car_devices.hpp"

#include <cmath>

namespace sweepmap {
namespace {

template <class T>
std::vector<int64_t> stamps(const std::vector<T>& items) {
  std::vector<int64_t> due;
  due.reserve(items.size());
  for (const T& i : items) due.push_back(i.utime);
  return due;
}

int64_t periodUs(double rate_hz) { return static_cast<int64_t>(std::llround(1e6 / rate_hz)); }

}  // namespace

SimImu::SimImu(SimMobile* car) {
  std::vector<ImuSample> s = car->imu();
  std::vector<int64_t> due = stamps(s);
  feed_ = TimedFeed<ImuSample>(std::move(s), std::move(due), periodUs(car->config().imu_rate_hz));
}

SimWheels::SimWheels(SimMobile* car) {
  std::vector<WheelTicks> t = car->wheelTicks();
  std::vector<int64_t> due = stamps(t);
  feed_ = TimedFeed<WheelTicks>(std::move(t), std::move(due),
                                periodUs(car->config().wheel_ticks_rate_hz));
}

SimCarLidar::SimCarLidar(SimMobile* car) {
  std::vector<Scan2D> scans = car->scans();
  std::vector<int64_t> due;
  due.reserve(scans.size());
  for (const Scan2D& s : scans) due.push_back(car->scanDeliveryUtime(s));
  feed_ = TimedFeed<Scan2D>(std::move(scans), std::move(due), periodUs(car->config().scan_rate_hz));
}

SimCarTruth::SimCarTruth(const SimMobile& car) {
  std::vector<TruthPose> t = car.truth();
  std::vector<int64_t> due = stamps(t);
  feed_ = TimedFeed<TruthPose>(std::move(t), std::move(due), periodUs(car.config().truth_rate_hz));
}

}  // namespace sweepmap
