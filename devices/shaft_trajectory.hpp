// The true motion of a simulated shaft as piecewise constant-acceleration segments.
// The simulated stepper produces segments; the simulated lidar (in-process, or in
// another process via TRUTH_SHAFT) evaluates the angle at each ray's time.
#pragma once

#include <cmath>
#include <cstdint>
#include <deque>
#include <optional>

namespace sweepmap {

struct ShaftSegment {
  int64_t start_utime = 0;
  double angle_rad = 0.0;       // at start_utime
  double velocity_rad_s = 0.0;  // at start_utime
  double accel_rad_s2 = 0.0;    // constant until the next segment
};

// Where the angle crosses a level: tau_s after the start of the segment it lies in.
struct ShaftCrossing {
  int64_t segment_start_utime = 0;
  double tau_s = 0.0;
  bool up = false;  // crossed the upper level going up (false: the lower level going down)
  double utime() const { return double(segment_start_utime) + tau_s * 1e6; }
  int64_t ns() const { return segment_start_utime * 1000 + std::llround(tau_s * 1e9); }
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
  // The first time in [from_ns, to_ns] (ns = utime * 1000: sub-microsecond, for step
  // timing) at which the angle crosses upper_rad going up or lower_rad going down. The last
  // segment extends forever. Solved in closed form per segment; a crossing exactly at a
  // segment boundary is found once.
  std::optional<ShaftCrossing> firstCrossing(int64_t from_ns, int64_t to_ns, double lower_rad,
                                             double upper_rad) const;
  // Forgets segments that ended before `utime` (keeps the one active at `utime`).
  void pruneBefore(int64_t utime);
  const std::deque<ShaftSegment>& segments() const { return segments_; }

 private:
  const ShaftSegment& active(int64_t utime) const;
  std::deque<ShaftSegment> segments_;
};

}  // namespace sweepmap
