// Which device a process opens: `lidar.device`, `imu.device`, `wheels.device` or
// `motor.device` in the rig file or `--device` on the command line. Forms: sim |
// scip://HOST[:PORT] | ydlidar:///dev/ttyUSB0[?baud=N] | rplidar:///dev/ttyUSB0[?baud=N] |
// hi219:///dev/ttyUSB1[?baud=N] | wheelboard:///dev/ttyACM0[?baud=N] |
// gpiod://CHIP?step=N&dir=N&enable=N&home=N[&OPTION=V...] (rig A's stepper driver and home
// switch on GPIO lines, libgpiod).
//
// gpiod: CHIP is what gpiod_chip_open_lookup() takes: a name (gpiochip0), a number, a label
// or a path (gpiod:///dev/gpiochip0). step, dir, enable and home are line offsets on that
// chip (on a Raspberry Pi's gpiochip0 the BCM numbers), all four required and distinct.
// Options and their defaults:
//   enable_active=low   level that enables the driver (A4988/DRV8825 ~EN, TB6600 ENA: low)
//   dir_positive=high   DIR level that turns the shaft in the positive direction
//   home_blocked=high   home input level while the sheet blocks the beam (an NPN
//                       light-on photo-interrupter with pull-up, slot-sensor modules)
//   home_pull=up        bias of the home input: up | down | none
#pragma once

#include <map>
#include <string>
#include <vector>

namespace sweepmap {

enum class DeviceProtocol { kSim, kScip, kYdlidarX4, kRplidar, kHi219, kWheelBoard, kGpiod };

enum class GpioPull { kUp, kDown, kNone };

// The lines of a gpiod:// URI (see above).
struct GpioLines {
  std::string chip;
  int step = -1;  // line offsets
  int dir = -1;
  int enable = -1;
  int home = -1;
  bool enable_active_low = true;
  bool dir_positive_high = true;
  bool home_blocked_high = true;
  GpioPull home_pull = GpioPull::kUp;
};

struct DeviceUri {
  DeviceProtocol protocol = DeviceProtocol::kSim;
  std::string text;  // as given
  std::string host;  // scip
  int port = 0;      // scip: 10940 unless given
  std::string path;  // serial device
  int baud = 0;      // serial: 128000 (X4) / 115200 (the others) unless ?baud=N
  GpioLines gpio;    // gpiod
  bool isSerial() const {
    return protocol != DeviceProtocol::kSim && protocol != DeviceProtocol::kScip &&
           protocol != DeviceProtocol::kGpiod;
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
constexpr int kGpioMaxLineOffset = 65535;

// Throws std::invalid_argument naming the URI and what is wrong with it.
DeviceUri parseDeviceUri(const std::string& text);

// "scip" | "ydlidar" | "rplidar" | "hi219" | "wheelboard" | "gpiod" | "sim"
const char* protocolName(DeviceProtocol protocol);

// For a rig file key: parses `text` and checks that it names a device of the right kind
// (`allowed`: the protocols that key takes, sim always). Throws std::invalid_argument naming
// the URI and the protocols the key takes.
DeviceUri parseDeviceUriFor(const std::string& text, const std::vector<DeviceProtocol>& allowed);

}  // namespace sweepmap
