// A synthetic sweep of a rotating 2D lidar standing inside an empty box room, for tests
// and benchmarks of the mapping code (not a simulation of the rig: no timing, no errors
// other than range noise). Map frame, metres: the room is an axis-aligned box, z up.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace sweepmap {

struct RoomSweepSpec {
  Eigen::Vector3f room_min_m{0.0f, 0.0f, 0.0f};
  Eigen::Vector3f room_max_m{8.0f, 6.0f, 3.0f};
  Eigen::Vector3f sensor_m{4.0f, 3.0f, 1.5f};  // strictly inside the room
  int scans = 640;                   // scan planes per sweep (mode 7: 180 deg / 0.28125 deg)
  int beams = 1081;                  // rays per scan plane
  double fov_deg = 270.0;            // scan sector, centred on +z (up)
  double range_noise_sigma_m = 0.0;  // Gaussian noise along each ray
  uint32_t seed = 1;                 // for the noise
};

// scans * beams points. Scan plane k contains the z axis through the sensor and turns by
// k / scans * 180 deg about it; beam j is at -fov/2 + j * fov / (beams - 1) from +z in that
// plane. Each point is where its ray leaves the box (walls, floor or ceiling). Deterministic.
std::vector<Eigen::Vector3f> syntheticRoomSweep(const RoomSweepSpec& spec);

}  // namespace sweepmap
