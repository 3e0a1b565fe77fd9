// The true motion of a simulated shaft as piecewise constant-acceleration segments.
// The simulated stepper produces segments; the simulated lidar (in-process, or in
// another process via TRUTH_SHAFT) evaluates the angle at each ray's time.
#pragma once

#include <cstdint>
#include <deque>

namespace sweepmap {

struct ShaftSegment {
  int64_t start_utime = 0;
  double angle_rad = 0.0;       // at start_utime
  double velocity_rad_s = 0.0;  // at start_utime
  double accel_rad_s2 = 0.0;    // constant until the next segment
};

class ShaftTrajectory {
 public:
  // Appends `s`, first dropping every segment that starts at or after s.start_utime
  // (a new command replaces the planned future).
  void apply(const ShaftSegment& s);
  bool empty() const { return segments_.empty(); }
  // True if some segment starts at or before `utime`.
  bool covers(int64_t utime) const;
  // Angle [rad] / velocity [rad/s] at `utime`; before the first segment: the first segment's
  // start values.
  double angleAt(int64_t utime) const;
  double velocityAt(int64_t utime) const;
  // Forgets segments that ended before `utime` (keeps the one active at `utime`).
  void pruneBefore(int64_t utime);
  const std::deque<ShaftSegment>& segments() const { return segments_; }

 private:
  const ShaftSegment& active(int64_t utime) const;
  std::deque<ShaftSegment> segments_;
};

}  // namespace sweepmap
