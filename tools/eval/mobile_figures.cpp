#include "tools/eval/mobile_figures.hpp"

#include <vector>

#include "mapping/plot.hpp"
#include "tools/eval/common.hpp"

namespace sweepmap::eval {
namespace {

// The track as points at height `z_m` (a top view's z band keeps them).
std::vector<Eigen::Vector3f> pathPoints(const PoseTrack& track, float z_m = 0.0f) {
  std::vector<Eigen::Vector3f> out;
  for (const auto& [utime, p] : track.poses()) {
    out.emplace_back(static_cast<float>(p.x_m), static_cast<float>(p.y_m), z_m);
  }
  return out;
}

std::vector<Eigen::Vector3f> sideView(const std::vector<Eigen::Vector3f>& cloud,
                                      int horizontal_axis) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(cloud.size());
  for (const auto& p : cloud) out.emplace_back(p[horizontal_axis], p.z(), 0.0f);
  return out;
}

Series histogramSeries(const DeviationStats& d, const std::string& title, const std::string& color,
                       const std::string& style) {
  Series s;
  s.title = title + ": " + d.rmsLabel();
  s.color = color;
  s.style = style;
  for (size_t i = 0; i < d.bins.size(); ++i) {
    s.x.push_back(d.binCenterMm(i));
    s.y.push_back(static_cast<double>(d.bins[i]));
  }
  return s;
}

void trajectoryFigure(const MobileEvaluation& ev, Figures* fig) {
  std::vector<Layer> layers;
  layers.push_back({"wheel odometry", "red", pathPoints(ev.log.wheels)});
  layers.push_back({"EKF", "blue", pathPoints(ev.log.ekf)});
  if (ev.hasTruth()) layers.push_back({"truth", "black", pathPoints(ev.log.truth)});
  PlotOptions po;
  po.title = ev.hasTruth() ? "Trajectory: wheel odometry alone (red), EKF (blue, under the truth "
                             "where it agrees), truth (black)"
                           : "Trajectory: wheel odometry alone (red), EKF (blue)";
  po.point_size = 0.15;
  fig->add("trajectory.png", "The car's path in the world frame (its start pose).",
           [&](const std::string& png) { plotTopView(png, layers, po); });
}

void trajectoryErrorFigure(const MobileEvaluation& ev, Figures* fig) {
  SeriesPlotOptions so;
  so.title = "Position error against the truth";
  so.x_label = "time [s]";
  so.y_label = "error [m]";
  const std::vector<Series> s = {
      {"wheel odometry", ev.odometry.t_s, ev.odometry.error_m, "lines", "red"},
      {"EKF", ev.ekf.t_s, ev.ekf.error_m, "lines", "blue"}};
  fig->add("trajectory_error.png",
           "Position error of wheel odometry alone and of the EKF; slip makes odometry drift.",
           [&](const std::string& png) { plotSeries(png, s, so); });
}

void topViewFigure(const MobileEvaluation& ev, Figures* fig) {
  PlotOptions po;
  po.point_size = 0.12;
  po.title = "Top view of the cloud (below 2 m) with the EKF path";
  po.z_band_m = PlotRange{0.05, 2.0};
  fig->add("top_view.png", "Top view (Fig. 11B): the cloud without floor and ceiling.",
           [&](const std::string& png) {
             plotTopView(png,
                         {{"cloud", "gray40", ev.cloud},
                          {"EKF path", "blue", pathPoints(ev.track(), 1.0f)}},
                         po);
           });
}

// axis 0: x-z, 1: y-z.
void sideViewFigure(const MobileEvaluation& ev, int axis, Figures* fig) {
  PlotOptions so;
  so.point_size = 0.12;
  so.x_label = axis == 0 ? "x [m]" : "y [m]";
  so.y_label = "z [m]";
  so.title = std::string("Side view of the cloud (") + (axis == 0 ? "x" : "y") + "-z)";
  const std::string file = std::string("side_view_") + (axis == 0 ? "xz" : "yz") + ".png";
  fig->add(file, "Side view: walls should stand vertical, floor and ceiling flat.",
           [&](const std::string& png) {
             plotTopView(png, {{"cloud", "gray40", sideView(ev.cloud, axis)}}, so);
           });
}

// Fig. 9 for `name` ("ceiling" or "walls"): the deviations before and after calibration.
void deviationComparisonFigure(const std::string& name, const DeviationStats& before,
                               const DeviationStats& after, Figures* fig) {
  SeriesPlotOptions so;
  so.title = "Fig. 9: deviations of the " + name + " points from their RANSAC plane";
  so.x_label = "deviation [mm]";
  so.y_label = "points";
  const std::vector<Series> s = {histogramSeries(before, "uncalibrated", "#cc3311", "boxes"),
                                 histogramSeries(after, "calibrated", "#1f4fd8", "lines")};
  fig->add("deviation_" + name + ".png",
           "Fig. 9: histogram of the " + name +
               " deviations before (red) and after (blue) the mounting calibration; the "
               "calibrated one should be narrower.",
           [&](const std::string& png) { plotSeries(png, s, so); });
}

// Fig. 9 without a comparison: ceiling and walls.
void deviationsFigure(const RoomMeasures& room, Figures* fig) {
  SeriesPlotOptions so;
  so.title = "Deviations of the ceiling and wall points from their RANSAC planes";
  so.x_label = "deviation [mm]";
  so.y_label = "points";
  const std::vector<Series> s = {histogramSeries(room.ceiling, "ceiling", "#1f4fd8", "lines"),
                                 histogramSeries(room.walls, "walls", "#228833", "lines")};
  fig->add("deviations.png", "Fig. 9: histograms of the plane deviations.",
           [&](const std::string& png) { plotSeries(png, s, so); });
}

void loopClosureFigure(const MobileEvaluation& ev, Figures* fig) {
  const LoopClosure& lc = ev.loop;
  const size_t scans = ev.log.scans.size();
  const std::vector<Eigen::Vector3f> pe =
      pointsOfScans(ev.cloud, ev.scan_of_point, lc.early, scans);
  const std::vector<Eigen::Vector3f> pl = pointsOfScans(ev.cloud, ev.scan_of_point, lc.late, scans);
  PlotOptions po;
  po.point_size = 0.2;
  po.z_band_m = PlotRange{0.9, 1.1};
  po.title = "Where the loop closes: first pass (blue) and last pass (red), z 0.9-1.1 m; ghost " +
             (lc.ghost_m ? fixed(1000.0 * *lc.ghost_m, 1) + " mm" : std::string("n/a"));
  fig->add("loop_closure.png",
           "Fig. 11C-D: the walls seen where the drive comes back to its start, first pass "
           "against last pass; a double wall is the ghost.",
           [&](const std::string& png) {
             plotTopView(png, {{"first pass", "blue", pe}, {"last pass", "red", pl}}, po);
           });
}

// The circle's plots: the halves' points at the lidar's height.
PlotOptions circlePlotOptions(const std::string& name, const HalfScanGhost& g) {
  PlotOptions po;
  po.point_size = 0.2;
  po.z_band_m = PlotRange{0.9, 1.1};
  po.title =
      "Calibration circle, " + name +
      " calibration: left (blue) and right (red) halves of the scans, z 0.9-1.1 m; double wall " +
      (g.walls.max_m ? fixed(1000.0 * *g.walls.max_m, 1) + " mm" : std::string("n/a"));
  return po;
}

}  // namespace

void drawMobileFigures(const MobileEvaluation& ev, Figures* fig) {
  trajectoryFigure(ev, fig);
  if (ev.hasTruth()) trajectoryErrorFigure(ev, fig);
  topViewFigure(ev, fig);
  for (int axis : {0, 1}) sideViewFigure(ev, axis, fig);
  if (ev.before) {
    deviationComparisonFigure("ceiling", ev.before->ceiling, ev.room.ceiling, fig);
    deviationComparisonFigure("walls", ev.before->walls, ev.room.walls, fig);
  } else {
    deviationsFigure(ev.room, fig);
  }
  if (!ev.loop.late.empty()) loopClosureFigure(ev, fig);
}

void circleGhostFigure(const std::string& name, const HalfScanGhost& g, Figures* fig) {
  const PlotOptions po = circlePlotOptions(name, g);
  fig->add(
      "circle_ghost_" + name + ".png",
      "Fig. 6-7: the calibration circle sees every wall with both halves of the scan; " + name +
          " calibration" +
          (name == "before" ? ", the mounting error splits each wall in two (the ghost)."
                            : ", the two halves coincide."),
      [&](const std::string& png) {
        plotTopView(png, {{"left halves", "blue", g.left}, {"right halves", "red", g.right}}, po);
      });
}

void targetGhostFigure(const std::string& name, const HalfScanGhost& g,
                       const Eigen::AlignedBox3d& target_world, Figures* fig) {
  PlotOptions zo = circlePlotOptions(name, g);
  const Eigen::Vector3d c = target_world.center();
  zo.x_range_m = PlotRange{c.x() - 0.8, c.x() + 0.8};
  zo.y_range_m = PlotRange{c.y() - 0.8, c.y() + 0.8};
  zo.z_band_m = PlotRange{target_world.min().z(), target_world.max().z()};
  zo.point_size = 0.4;
  zo.title = "Calibration target (board before a window), " + name +
             " calibration: left halves (blue), right halves (red)";
  fig->add(
      "target_ghost_" + name + ".png",
      "Fig. 6-7, close up: the board in front of the window recess at the board's height, " + name +
          " calibration" + (name == "before" ? ": two boards." : ": one board."),
      [&](const std::string& png) {
        plotTopView(png, {{"left halves", "blue", g.left}, {"right halves", "red", g.right}}, zo);
      });
}

}  // namespace sweepmap::eval
