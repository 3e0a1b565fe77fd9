// The simulated worlds behind the emulators, as scan sources on the emulator's clock.
//  - rotating_lidar rigs (the UST-10LX of rig A): the simulated lidar on the simulated
//    shaft. The shaft stands still at angle 0, or, with follow_lcm, follows TRUTH_SHAFT from
//    a simulated stepper in another process (`sweepmap-motor --sim`); then the world also
//    publishes TRUTH_RIG and TRUTH_SWEEP, as `sweepmap-lidar --sim` does.
//  - mobile_lidar rigs (the X4 of rig B; RPLIDAR; the HI219 and the wheel board): the simulated
//    car driving its path (then standing at its end: the IMU and the board fall silent), its
//    360° lidar's scans, each handed out as it begins (the path is scripted, so its rays are
//    known ahead) for devices that send every sample at its own time; its IMU samples and
//    encoder readings at their times. With publish_truth the world publishes the car's truth.
// A device's scan timing follows its own oscillator: with a clock drift of p ppm the scans
// come (1 + p·1e-6) times as often in true time, as a real mirror/motor timed by that
// oscillator does.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "processes/node.hpp"
#include "sim/beam.hpp"
#include "tools/emulate/emulated_lidar.hpp"
#include "tools/emulate/odometry_emulators.hpp"

namespace sweepmap {

struct EmulatorWorldOptions {
  std::string rig;                     // file or name
  std::string scene;                   // file or name; "" = the rig kind's default
  std::vector<std::string> overrides;  // key=value (scene.* to the scene)
  uint64_t seed = 1;
  double clock_drift_ppm = 0.0;
  bool follow_lcm = false;     // rotating rigs: follow TRUTH_SHAFT, publish truth
  bool publish_truth = false;  // mobile rigs: publish TRUTH_POSE and TRUTH_MOUNTING on LCM
};

class EmulatorWorld {
 public:
  virtual ~EmulatorWorld() = default;
  // Scans completed (delivered) by now_us, each once, their rays on the motor's grid of
  // angles; with a beam offset (the device's: beamOffsetOf, tools/emulate/devices.hpp) each
  // ray looks where that beam does (Scan2D::angles_rad). Safe to call from any thread. Throws
  // std::runtime_error for a beam offset in a world without it (rotating_lidar rigs).
  virtual ScanSource source(const BeamOffset& beam) = 0;
  // mobile_lidar worlds: the car's IMU samples and encoder readings by now_us, each once.
  // Throws std::runtime_error for a world without them.
  virtual ImuSource imuSource();
  virtual TicksSource ticksSource();
  // Nodes to run over LCM alongside the server (empty unless follow_lcm), and messages to
  // publish once at start (TRUTH_RIG).
  virtual std::vector<Node*> nodes() { return {}; }
  virtual std::vector<Message> startMessages(int64_t now_us) { return {}; }
  // The rig's lidar.model (core/lidar_models.hpp): what a SCIP emulator answers as.
  virtual std::string lidarModel() const = 0;
};

// Throws ConfigError / std::runtime_error naming the file and key.
std::unique_ptr<EmulatorWorld> makeEmulatorWorld(const EmulatorWorldOptions& options,
                                                 int64_t start_utime);

}  // namespace sweepmap
