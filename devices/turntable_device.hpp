// A turntable with an encoder on its axis (rig C, Zhao 2021), as sweepmap-profiler sees it:
// real (no driver yet: no protocol chosen) or simulated (sim/profile_devices.hpp).
// Angles are encoder angles: 2 pi counts / counts_per_revolution, before the encoder's zero
// (core/profile_geometry.hpp), positive clockwise seen from above.
#pragma once

#include <cstdint>
#include <vector>

#include "devices/lidar_device.hpp"

namespace sweepmap {

// Move to `target_deg` (encoder angle) at `speed_deg_s` (> 0) and stop there. A new command
// replaces the one under way from where the table is.
struct TurntableCommand {
  double target_deg = 0.0;
  double speed_deg_s = 0.0;
};

// One encoder reading, stamped by the device (the servo controller's latch time).
struct EncoderSample {
  int64_t utime = 0;
  int64_t counts = 0;  // not wrapped
};

class TurntableDevice {
 public:
  virtual ~TurntableDevice() = default;
  virtual void command(int64_t now_utime, const TurntableCommand& cmd) = 0;
  // Encoder samples up to `now_utime`, in time order, each once.
  virtual std::vector<EncoderSample> poll(int64_t now_utime) = 0;
  virtual int countsPerRevolution() const = 0;
  virtual DeviceHealth health() { return {}; }
};

}  // namespace sweepmap
