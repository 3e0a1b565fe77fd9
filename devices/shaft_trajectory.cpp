#include "devices/shaft_trajectory.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <stdexcept>

namespace sweepmap {
namespace {

// Roots this close outside a piece still count (clamped), so that a crossing exactly at a
// segment boundary is not lost to rounding on both sides; much finer than the 1 us clock.
constexpr double kRootSlackS = 1e-9;

// Earliest tau in [from_s, to_s] (give or take kRootSlackS) at which
// angle0 + v*tau + a*tau^2/2 crosses `level` upward (up = true) or downward.
std::optional<double> firstCrossingS(double angle0, double v, double a, double level, bool up,
                                     double from_s, double to_s) {
  std::array<double, 2> roots{};
  size_t n = 0;
  const double c = angle0 - level;
  if (a == 0.0) {
    if (v != 0.0) roots[n++] = -c / v;
  } else {
    const double disc = v * v - 2.0 * a * c;
    if (disc < 0.0) return std::nullopt;
    // Numerically stable roots of (a/2) tau^2 + v tau + c.
    const double q = -0.5 * (v + std::copysign(std::sqrt(disc), v));
    if (q != 0.0) {
      roots[n++] = q / (0.5 * a);
      roots[n++] = c / q;
    } else {
      roots[n++] = 0.0;  // v = 0 and c = 0
    }
    if (n == 2 && roots[1] < roots[0]) std::swap(roots[0], roots[1]);
  }
  for (size_t i = 0; i < n; ++i) {
    const double tau = roots[i];
    if (tau < from_s - kRootSlackS || tau > to_s + kRootSlackS) continue;
    const double slope = v + a * tau;
    const double direction = slope != 0.0 ? slope : a;  // touching at rest: where it goes next
    if (up ? direction > 0.0 : direction < 0.0) return std::clamp(tau, from_s, to_s);
  }
  return std::nullopt;
}

}  // namespace

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

std::optional<ShaftCrossing> ShaftTrajectory::firstCrossing(int64_t from_ns, int64_t to_ns,
                                                            double lower_rad,
                                                            double upper_rad) const {
  auto it = std::upper_bound(
      segments_.begin(), segments_.end(), from_ns,
      [](int64_t t_ns, const ShaftSegment& s) { return t_ns < s.start_utime * 1000; });
  if (it != segments_.begin()) --it;
  for (; it != segments_.end() && it->start_utime * 1000 <= to_ns; ++it) {
    const int64_t start_ns = it->start_utime * 1000;
    const auto next = std::next(it);
    const int64_t piece_end_ns =
        next == segments_.end() ? to_ns : std::min(next->start_utime * 1000, to_ns);
    const int64_t piece_start_ns = std::max(start_ns, from_ns);
    if (piece_end_ns < piece_start_ns) continue;
    const double from_s = double(piece_start_ns - start_ns) * 1e-9;
    const double to_s = double(piece_end_ns - start_ns) * 1e-9;
    const auto up = firstCrossingS(it->angle_rad, it->velocity_rad_s, it->accel_rad_s2, upper_rad,
                                   true, from_s, to_s);
    const auto down = firstCrossingS(it->angle_rad, it->velocity_rad_s, it->accel_rad_s2, lower_rad,
                                     false, from_s, to_s);
    if (!up && !down) continue;
    const bool moving_up = up && (!down || *up <= *down);
    return ShaftCrossing{it->start_utime, moving_up ? *up : *down, moving_up};
  }
  return std::nullopt;
}

void ShaftTrajectory::pruneBefore(int64_t utime) {
  // Segment 0 ends where segment 1 starts.
  while (segments_.size() >= 2 && segments_[1].start_utime <= utime) segments_.pop_front();
}

}  // namespace sweepmap
