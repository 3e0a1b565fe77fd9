// The protocol half of each real lidar driver (a LidarSession): SCIP 2.0 (Hokuyo UST-10LX /
// UST-20LX / URG), YDLIDAR X4 and RPLIDAR A1/A2. The same session decodes live bytes in the
// driver and a capture file offline (`sweepmap decode`), so both give the same scans.
#pragma once

#include <memory>

#include "core/device_uri.hpp"
#include "core/rig_components.hpp"
#include "drivers/real_lidar.hpp"

namespace sweepmap {

enum class ScanTime {
  // Host receive times: SCIP maps the device's stamps to host time (DeviceClockSync, with
  // the TM exchange of start() as the anchor); the serial devices, which stamp nothing,
  // date each sample from its packet's arrival. Live, and for captures.
  kArrival,
  // No receive times (a raw byte file): SCIP scans at their device stamp (ms, unwrapped),
  // serial devices at the time their bytes take on the line at the port's baud rate.
  kStream,
};

struct SessionOptions {
  ScanTime time = ScanTime::kArrival;
  int baud = 0;  // serial: for kStream times (0 = the protocol's default)
};

// Throws std::invalid_argument for DeviceProtocol::kSim.
std::unique_ptr<LidarSession> makeLidarSession(DeviceProtocol protocol, const LidarConfig& expected,
                                               const SessionOptions& options);

}  // namespace sweepmap
