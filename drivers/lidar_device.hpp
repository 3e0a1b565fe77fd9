// A 2D lidar as the lidar process sees it: real (serial/TCP) or simulated.
#pragma once

#include <cstdint>
#include <vector>

#include "core/scan.hpp"

namespace sweepmap {

class LidarDevice {
 public:
  virtual ~LidarDevice() = default;
  // Complete scans delivered up to `now_utime`, in time order, each once.
  virtual std::vector<Scan2D> poll(int64_t now_utime) = 0;
};

}  // namespace sweepmap
