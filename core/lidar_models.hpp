// The lidar models sweepmap knows, as data: what each device reports of itself (a SCIP
// sensor's PP reply: AMIN, AMAX, AFRT, ARES, DMIN, DMAX, SCAN) or what its datasheet gives
// (the serial 360° lidars). A rig file names one in `lidar.model`; its other lidar keys must
// then fit the model (a SCIP rig's rays are a run of the model's steps: the field of view the
// driver requests), and the driver checks the device it finds against it.
//
// SCIP angles (Hokuyo "Communication Protocol Specification for SCIP2.0", C-42-03320B, §5):
// step s looks at (s - AFRT) * 360° / ARES, counter-clockwise positive. A cluster of c steps
// s .. s+c-1 sends one value, the smallest of its steps (the specification's grouping rule);
// sweepmap puts that ray at the cluster's middle, step s + (c-1)/2, the expected direction of
// a minimum taken anywhere in the span. (urg_library and urg_node put it at the first step s,
// (c-1)/2 steps earlier; with c = 1, the only cluster our rigs use, the two agree.)
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/device_uri.hpp"
#include "core/rig_components.hpp"

namespace sweepmap {

// A SCIP sensor's PP values.
struct ScipGeometry {
  int dmin_mm = 0, dmax_mm = 0, ares = 0, amin = 0, amax = 0, afrt = 0, scan_rpm = 0;
  double stepRad() const;
  // The direction of (possibly fractional) step `step`, from the front step [rad].
  double angleRad(double step) const;
  // Time between two steps [s]: a turn of the mirror is ARES steps at SCAN rpm.
  double stepPeriodS() const { return 60.0 / scan_rpm / ares; }
};

struct LidarModel {
  std::string name;  // as lidar.model names it
  DeviceProtocol protocol = DeviceProtocol::kScip;
  ScipGeometry pp;  // SCIP models only
  // SCIP: the value the sensor sends for "no return" (an error code below DMIN), as the
  // emulator sends it.
  uint32_t no_return_code = 0;
  bool scip_intensity = false;                  // SCIP: answers ME/GE (ranges and intensities)
  double range_min_m = 0.0, range_max_m = 0.0;  // the specified measuring range
  double scan_rate_hz = 0.0;                    // standard (SCIP: SCAN / 60)
  double scan_rate_min_hz = 0.0, scan_rate_max_hz = 0.0;
  double sample_rate_hz = 0.0;  // serial: samples per second in the standard scan
  // Serial: what the device reports of itself. X4: the model code of its device info (6);
  // RPLIDAR: the family, the high nibble of GET_INFO's model byte (1 = A1, 2 = A2).
  int model_code = -1;
  std::string source;  // where the numbers come from
};

const std::vector<LidarModel>& lidarModels();
// nullptr for a name that is not in the catalogue.
const LidarModel* findLidarModel(const std::string& name);
// "UST-10LX | UST-20LX | ..." for messages and help texts.
std::string lidarModelNames();

// The steps a rig's lidar asks a SCIP model for: ray i covers steps start + i*cluster ..
// start + i*cluster + cluster - 1.
// A rig's lidar keys that do not fit its model: `key` (without prefix) and why.
class LidarFitError : public std::invalid_argument {
 public:
  LidarFitError(std::string key_name, const std::string& why)
      : std::invalid_argument(why), key(std::move(key_name)) {}
  std::string key;
};

struct ScipRequest {
  int start_step = 0, end_step = 0, cluster = 1;
};

// Throws LidarFitError naming the lidar key and why, when `lidar`
// does not fit `model`: a SCIP rig's angle_increment_deg must be a whole number of steps
// (the cluster), angle_min_deg the middle of a cluster, its rays within AMIN..AMAX,
// steps_per_revolution ARES, scan_rate_hz SCAN / 60; every model's range limits within the
// model's and its scan rate within the model's.
void checkLidarFitsModel(const LidarConfig& lidar, const LidarModel& model);

// The steps of a SCIP rig (checkLidarFitsModel checks them; throws LidarFitError).
ScipRequest scipRequestFor(const LidarConfig& lidar, const LidarModel& model);

// The lidar keys of a model's whole field of view at its standard rate (`sweepmap decode
// --lidar-model`): SCIP steps AMIN..AMAX with DMIN..DMAX; a serial lidar's turn on a grid of
// sample_rate / scan_rate rays from -180°.
LidarConfig fullFieldOf(const LidarModel& model);

}  // namespace sweepmap
