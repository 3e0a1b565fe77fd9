// A 2D lidar as the lidar process sees it: real (serial/TCP) or simulated.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/scan.hpp"

namespace sweepmap {

// What a device driver tells the process's status: cumulative counters and its events.
struct DeviceHealth {
  std::vector<std::pair<std::string, int64_t>> counters;  // e.g. {"reconnects", 2}
  std::vector<std::string> events;  // since the last call: "scip://...: connection refused"
  std::string fatal;                // non-empty: the device cannot be used (identity mismatch)

  // The counter `name`, or -1 when the device keeps no such counter.
  int64_t counter(const std::string& name) const {
    for (const auto& [k, v] : counters) {
      if (k == name) return v;
    }
    return -1;
  }
};

class LidarDevice {
 public:
  virtual ~LidarDevice() = default;
  // Complete scans delivered up to `now_utime`, in time order, each once.
  virtual std::vector<Scan2D> poll(int64_t now_utime) = 0;
  // Counters and events since the last call (real drivers); a simulation has none.
  virtual DeviceHealth health() { return {}; }
};

}  // namespace sweepmap
