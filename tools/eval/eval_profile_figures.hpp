// The PNGs of rig C's paper experiment: S(M, N) as Zhao 2021 Fig. 6, the test piece's cloud
// (Fig. 9) under our calibration, and the features' errors per setting with error bars.
#pragma once

#include "tools/eval/eval_profile_report.hpp"
#include "tools/eval/figures.hpp"

namespace sweepmap::eval {

void drawProfileFigures(const ProfileEvaluation& ev, Figures* figures);

}  // namespace sweepmap::eval
