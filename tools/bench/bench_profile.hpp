// Rig-C part of `sweepmap bench`: the axis-offset calibration on the default simulated plates
// (the point subset `sweepmap calib axis-offset` uses by default): ours (Ceres, with the
// laser tilt, the covariance and the observability check) against the paper's grid search
// (Algorithm 1) over its interval at its 1 mm and at 0.1 mm (10x finer). Prints figures;
// asserts nothing.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>

namespace sweepmap {

struct ProfileBenchOptions {
  std::string rig = "rig_c";  // path or name
  uint64_t seed = 1;
  int repeats = 3;  // ours is timed this many times (median printed)
};

// Returns 0.
int benchProfile(const ProfileBenchOptions& options, std::ostream& out);

}  // namespace sweepmap
