#include "mapping/synthetic_room.hpp"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace sweepmap {

std::vector<Eigen::Vector3f> syntheticRoomSweep(const RoomSweepSpec& spec) {
  if (spec.scans <= 0 || spec.beams < 2) throw std::invalid_argument("syntheticRoomSweep: counts");
  if (!((spec.sensor_m.array() > spec.room_min_m.array()).all() &&
        (spec.sensor_m.array() < spec.room_max_m.array()).all())) {
    throw std::invalid_argument("syntheticRoomSweep: sensor outside the room");
  }
  constexpr double kPi = 3.14159265358979323846;
  const Eigen::Vector3d s = spec.sensor_m.cast<double>();
  const Eigen::Vector3d lo = spec.room_min_m.cast<double>();
  const Eigen::Vector3d hi = spec.room_max_m.cast<double>();
  std::mt19937 rng(spec.seed);
  std::normal_distribution<double> noise(0.0, spec.range_noise_sigma_m);

  std::vector<Eigen::Vector3f> points;
  points.reserve(static_cast<size_t>(spec.scans) * static_cast<size_t>(spec.beams));
  const double fov = spec.fov_deg * kPi / 180.0;
  for (int k = 0; k < spec.scans; ++k) {
    const double phi = kPi * k / spec.scans;
    for (int j = 0; j < spec.beams; ++j) {
      const double theta = -fov / 2 + fov * j / (spec.beams - 1);
      const Eigen::Vector3d d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
      // Distance to the first wall along d (the sensor is inside, so every t > 0).
      double t = std::numeric_limits<double>::infinity();
      for (int a = 0; a < 3; ++a) {
        if (d[a] > 1e-12) t = std::min(t, (hi[a] - s[a]) / d[a]);
        if (d[a] < -1e-12) t = std::min(t, (lo[a] - s[a]) / d[a]);
      }
      if (spec.range_noise_sigma_m > 0.0) t += noise(rng);
      points.push_back((s + t * d).cast<float>());
    }
  }
  return points;
}

}  // namespace sweepmap
