// Rig C's simulated plate sweeps for the calibration tests: the default rig (config/rig_c.yaml)
// with overrides, its profiles per sweep as the calibration's plate poses.
#pragma once

#include <string>
#include <vector>

#include "calib/axis_offset.hpp"
#include "rigs/rotating_profile.hpp"

namespace sweepmap {
namespace test {

inline RotatingProfileConfig rigC(const std::vector<std::string>& sets = {}) {
  return loadRotatingProfileConfig(std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_c.yaml", sets);
}

// One PlanePoints per plate pose, from the simulator (as the log reader would make them).
inline std::vector<PlanePoints> simulatedPlates(const RotatingProfileConfig& rig, uint64_t seed,
                                                int max_points = 20000) {
  SimProfiler profiler(rig.profiler, rig.turntable, rig.sim, seed);
  std::vector<PlanePoints> planes;
  int32_t id = 0;
  for (const PlatePose& pose : platePoses(rig.sim, rig.turntable)) {
    PlanePoints plane{"sweep " + std::to_string(id), {}};
    for (const Profile& p : profiler.sweep(ProfileScene::plate(pose), id, 0)) {
      const double a = 2 * M_PI * p.encoder_counts / p.counts_per_revolution;
      for (size_t i = 0; i < p.y_mm.size(); ++i) plane.samples.push_back({p.y_mm[i], p.z_mm[i], a});
    }
    planes.push_back(subsample(plane, max_points));
    ++id;
  }
  return planes;
}

}  // namespace test
}  // namespace sweepmap
