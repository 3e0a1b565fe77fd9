// The emulated lidar models by name, each a protocol engine fed by a simulated world.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "sim/beam.hpp"
#include "tools/emulate/emulated_lidar.hpp"

namespace sweepmap {

enum class EmulatedModel {
  kUst10lx,    // Hokuyo UST-10LX: SCIP 2.0 over TCP (rotating_lidar worlds)
  kX4,         // YDLIDAR X4: serial, 128000 baud (mobile_lidar worlds)
  kRplidarA1,  // Slamtec RPLIDAR A1: serial, 115200 baud (mobile_lidar worlds)
};

// "ust10lx" | "x4" | "rplidar"; throws std::invalid_argument.
EmulatedModel emulatedModel(const std::string& name);

// The sensor's own clock (SCIP time stamps, TM): at true time t [us] after power-on at
// power_on_us its millisecond counter reads
//   (start_ms + offset_ms + (t - power_on_us) (1 + drift_ppm 1e-6) / 1000) mod 2^24.
struct EmulatedClock {
  int64_t start_ms = 0;
  double offset_ms = 0.0;
  double drift_ppm = 0.0;
  int64_t counterAt(int64_t power_on_us, int64_t t_us) const;
};

// Where the model's beam looks off its motor angle (sim/beam.hpp): the X4's AngCorrect; empty
// for the others, which measure along their motor angle.
BeamOffset beamOffsetOf(EmulatedModel model);

// kUst10lx serves SCIP as `scip_model` (a SCIP model of core/lidar_models.hpp: the world rig's
// lidar.model, so `--set lidar.model=URG-04LX-UG01` emulates a URG-04LX-UG01).
std::unique_ptr<EmulatedLidar> makeEmulatedLidar(EmulatedModel model, ScanSource source,
                                                 const EmulatedClock& clock, int64_t power_on_us,
                                                 const std::string& scip_model = "UST-10LX");

}  // namespace sweepmap
