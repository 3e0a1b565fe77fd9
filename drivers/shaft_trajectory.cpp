#include "drivers/shaft_trajectory.hpp"

#include <algorithm>
#include <iterator>
#include <stdexcept>

namespace sweepmap {

void ShaftTrajectory::apply(const ShaftSegment& s) {
  while (!segments_.empty() && segments_.back().start_utime >= s.start_utime) {
    segments_.pop_back();
  }
  segments_.push_back(s);
}

bool ShaftTrajectory::covers(int64_t utime) const {
  return !segments_.empty() && segments_.front().start_utime <= utime;
}

const ShaftSegment& ShaftTrajectory::active(int64_t utime) const {
  if (segments_.empty()) throw std::logic_error("ShaftTrajectory: evaluated while empty");
  const auto after =
      std::upper_bound(segments_.begin(), segments_.end(), utime,
                       [](int64_t t, const ShaftSegment& s) { return t < s.start_utime; });
  return after == segments_.begin() ? *after : *std::prev(after);
}

double ShaftTrajectory::angleAt(int64_t utime) const {
  const ShaftSegment& s = active(utime);
  const double dt_s = double(std::max<int64_t>(0, utime - s.start_utime)) * 1e-6;
  return s.angle_rad + dt_s * (s.velocity_rad_s + 0.5 * s.accel_rad_s2 * dt_s);
}

double ShaftTrajectory::velocityAt(int64_t utime) const {
  const ShaftSegment& s = active(utime);
  const double dt_s = double(std::max<int64_t>(0, utime - s.start_utime)) * 1e-6;
  return s.velocity_rad_s + s.accel_rad_s2 * dt_s;
}

void ShaftTrajectory::pruneBefore(int64_t utime) {
  // Segment 0 ends where segment 1 starts.
  while (segments_.size() >= 2 && segments_[1].start_utime <= utime) segments_.pop_front();
}

}  // namespace sweepmap
