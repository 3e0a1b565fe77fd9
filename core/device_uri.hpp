// Which device a process opens: `lidar.device`, `imu.device` or `wheels.device` in the rig
// file or `--device` on the command line. Forms: sim | scip://HOST[:PORT] |
// ydlidar:///dev/ttyUSB0[?baud=N] | rplidar:///dev/ttyUSB0[?baud=N] |
// hi219:///dev/ttyUSB1[?baud=N] | wheelboard:///dev/ttyACM0[?baud=N].
#pragma once

#include <map>
#include <string>
#include <vector>

namespace sweepmap {

enum class DeviceProtocol { kSim, kScip, kYdlidarX4, kRplidar, kHi219, kWheelBoard };

struct DeviceUri {
  DeviceProtocol protocol = DeviceProtocol::kSim;
  std::string text;  // as given
  std::string host;  // scip
  int port = 0;      // scip: 10940 unless given
  std::string path;  // serial device
  int baud = 0;      // serial: 128000 (X4) / 115200 (the others) unless ?baud=N
  bool isSerial() const {
    return protocol != DeviceProtocol::kSim && protocol != DeviceProtocol::kScip;
  }
  bool isLidar() const {
    return protocol == DeviceProtocol::kScip || protocol == DeviceProtocol::kYdlidarX4 ||
           protocol == DeviceProtocol::kRplidar;
  }
};

constexpr int kScipDefaultPort = 10940;  // the UST-10LX's factory setting
constexpr int kX4DefaultBaud = 128000;
constexpr int kRplidarDefaultBaud = 115200;
constexpr int kHi219DefaultBaud = 115200;  // the HI219's factory setting
constexpr int kWheelBoardDefaultBaud = 115200;

// Throws std::invalid_argument naming the URI and what is wrong with it.
DeviceUri parseDeviceUri(const std::string& text);

// "scip" | "ydlidar" | "rplidar" | "hi219" | "wheelboard" | "sim"
const char* protocolName(DeviceProtocol protocol);

// For a rig file key: parses `text` and checks that it names a device of the right kind
// (`allowed`: the protocols that key takes, sim always). Throws std::invalid_argument naming
// the URI and the protocols the key takes.
DeviceUri parseDeviceUriFor(const std::string& text, const std::vector<DeviceProtocol>& allowed);

}  // namespace sweepmap
