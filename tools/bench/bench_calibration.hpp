// Calibration part of `sweepmap bench` (issue 23): per rig kind, `sweepmap calib rig` on the
// recording `sweepmap calib plan` recommends, simulated with `sweepmap sim` (rig A: 10 mode-7
// sweeps, rig B: the figure-eight drive, rig C: the plates): its wall time, CPU time, peak
// RSS and each parameter's error against the simulator's truth. For rig B also the
// single-parameter `calib mounting` before issue 23 (its reference solver, 442 s when it was
// replaced) and today's, on the 120 s circle they were measured on, in the same run: times,
// mounting errors and the speed-up. Prints figures; asserts nothing.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "rigs/rig_file.hpp"

namespace sweepmap {

struct CalibrationBenchOptions {
  std::string work = "build/bench";  // scratch directory
  std::string sweepmap_exe;          // runs `sweepmap sim` and `sweepmap calib rig`
  double mounting_circle_s = 120.0;  // rig B: the circle of the old `calib mounting`
};

// One rig's figures; a step that fails says so and where its output is. Returns 0.
int benchCalibration(const CalibrationBenchOptions& options, const Rig& rig, std::ostream& out);

}  // namespace sweepmap
