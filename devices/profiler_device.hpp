// A line-structured-light profile sensor (rig C, Zhao 2021) as sweepmap-profiler sees it:
// real (no driver yet: no protocol chosen) or simulated (sim/profile_devices.hpp).
// A profile is the valid points (0, y, z) of one exposure in the laser plane, stamped with
// the exposure time, with the turntable encoder's count latched at the exposure (the
// profiler's encoder input, as a Gocator's: core/profile.hpp).
#pragma once

#include <cstdint>
#include <vector>

#include "core/profile.hpp"
#include "devices/lidar_device.hpp"

namespace sweepmap {

class ProfilerDevice {
 public:
  virtual ~ProfilerDevice() = default;
  // Profiles exposed up to `now_utime`, in time order, each once. Their sweep_id is 0: the
  // sweep is the process's to number.
  virtual std::vector<Profile> poll(int64_t now_utime) = 0;
  virtual DeviceHealth health() { return {}; }
};

}  // namespace sweepmap
