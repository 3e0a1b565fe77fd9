// Rig B's figures (Miao 2022 section 5): the trajectory and its error, top and side views of
// the cloud, the deviation histograms of Fig. 9, the loop's closing walls (Fig. 11) and the
// calibration circle's double walls (Fig. 6-7). Each function draws one PNG. Internal to
// tools/eval.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "tools/eval/figures.hpp"
#include "tools/eval/mobile_metrics.hpp"
#include "tools/eval/mobile_report.hpp"

namespace sweepmap::eval {

// The figures of one log, in the report's order: trajectory.png, trajectory_error.png (with
// truth), top_view.png, side_view_xz.png, side_view_yz.png, deviation_ceiling.png and
// deviation_walls.png (with a mounting before calibration) or deviations.png, and
// loop_closure.png (where the drive comes back to a place).
void drawMobileFigures(const MobileEvaluation& ev, Figures* fig);

// circle_ghost_<name>.png: the calibration circle's left and right scan halves with the
// mounting `name` ("before" or "after" the calibration).
void circleGhostFigure(const std::string& name, const HalfScanGhost& g, Figures* fig);

// target_ghost_<name>.png: the same, close up on the calibration target (`target_world`).
void targetGhostFigure(const std::string& name, const HalfScanGhost& g,
                       const Eigen::AlignedBox3d& target_world, Figures* fig);

}  // namespace sweepmap::eval
