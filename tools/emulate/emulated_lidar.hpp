// The protocol engine of an emulated lidar: bytes in from the host, bytes out of the device.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/scan.hpp"

namespace sweepmap {

// Simulated scans completed by now_us, each once, in order; utime = true time of the first
// ray on the emulator clock.
using ScanSource = std::function<std::vector<Scan2D>(int64_t now_us)>;

class EmulatedLidar {
 public:
  virtual ~EmulatedLidar() = default;
  // Bytes the host sent, arriving at now_us (emulator clock, monotonic us): replies → *out.
  virtual void receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) = 0;
  // Appends everything the device would have sent by now_us (streamed samples).
  virtual void advance(int64_t now_us, std::string* out) = 0;
  // Connection closed / power cycle: back to the power-on state (no stream).
  virtual void reset(int64_t now_us) = 0;
};

}  // namespace sweepmap
