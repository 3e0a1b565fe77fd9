// Which device a process opens: `lidar.device` in the rig file or `--device` on the command
// line. Forms: sim | scip://HOST[:PORT] | ydlidar:///dev/ttyUSB0[?baud=N] |
// rplidar:///dev/ttyUSB0[?baud=N].
#pragma once

#include <map>
#include <string>

namespace sweepmap {

enum class DeviceProtocol { kSim, kScip, kYdlidarX4, kRplidar };

struct DeviceUri {
  DeviceProtocol protocol = DeviceProtocol::kSim;
  std::string text;  // as given
  std::string host;  // scip
  int port = 0;      // scip: 10940 unless given
  std::string path;  // serial device
  int baud = 0;      // serial: 128000 (X4) / 115200 (RPLIDAR A1/A2) unless ?baud=N
  bool isSerial() const {
    return protocol == DeviceProtocol::kYdlidarX4 || protocol == DeviceProtocol::kRplidar;
  }
};

constexpr int kScipDefaultPort = 10940;  // the UST-10LX's factory setting
constexpr int kX4DefaultBaud = 128000;
constexpr int kRplidarDefaultBaud = 115200;

// Throws std::invalid_argument naming the URI and what is wrong with it.
DeviceUri parseDeviceUri(const std::string& text);

// "scip" | "ydlidar" | "rplidar" | "sim"
const char* protocolName(DeviceProtocol protocol);

}  // namespace sweepmap
