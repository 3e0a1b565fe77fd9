// Rig A's figures: Yuan 2021 Fig. 8 (top views), 9-10 (phi_error), 11 (E_map), A2 (wall
// deviations), 1 (the naive action sequence) and the alpha calibration's LM history. Each
// is drawn by one function in rotating_figures.cpp into one PNG. Internal to tools/eval.
#pragma once

#include "tools/eval/figures.hpp"
#include "tools/eval/rotating_report.hpp"

namespace sweepmap::eval {

// Every figure the data allow, in the report's order; the phi_error figures need the
// simulator's truth (`has_truth`).
void drawFigures(const ReportInput& in, const EvalSettings& s, bool has_truth, Figures* fig);

}  // namespace sweepmap::eval
