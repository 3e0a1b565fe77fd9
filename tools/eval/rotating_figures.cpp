#include "tools/eval/rotating_figures.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/angles.hpp"
#include "mapping/occupancy_map.hpp"
#include "mapping/plot.hpp"
#include "tools/eval/common.hpp"
#include "tools/offline/views_3d.hpp"

namespace sweepmap::eval {
namespace {

const char* methodColor(Method m) {
  switch (m) {
    case Method::kRayPlane:
      return "#1f4fd8";
    case Method::kCentroid:
      return "#1a9641";
    case Method::kUncorrected:
      return "#d7191c";
  }
  return "";
}

// --- Fig. 8: top views ------------------------------------------------------------------

void topViewFigure(int mode, const Group& g, const EvalSettings& s, Figures* fig) {
  fig->add("fig8_top_view_mode" + std::to_string(mode) + ".png",
           "Fig. 8, mode " + std::to_string(mode) + ": top view of its " +
               std::to_string(g.sweeps.size()) +
               " sweeps overlaid; red: uncorrected C_O' (attitude varies sweep to sweep), "
               "blue: corrected C_O (ray_plane; attitude nearly constant).",
           [&](const std::string& png) {
             PlotOptions po;
             po.title = "Mode " + std::to_string(mode) + ": " + std::to_string(g.sweeps.size()) +
                        " sweeps, top view (z " + fixed(s.top_view_z_min_m, 1) + ".." +
                        fixed(s.top_view_z_max_m, 1) + " m), C_O' red, C_O blue";
             po.z_band_m = PlotRange{s.top_view_z_min_m, s.top_view_z_max_m};
             po.point_size = 0.2;
             po.max_points_per_layer = 300000;
             plotTopView(
                 png, {{"uncorrected C_O'", "red", g.top_Op}, {"corrected C_O", "blue", g.top_O}},
                 po);
           });
}

// --- Fig. 9: phi_error per sweep -----------------------------------------------------------

// phi_error of every sweep by method; x = mode, the sweeps of a mode spread around it.
std::map<Method, Series> phiErrorPerSweep(const ReportInput& in) {
  std::map<Method, Series> per_sweep;
  for (Method m : {Method::kUncorrected, Method::kRayPlane, Method::kCentroid}) {
    per_sweep[m].title = m == Method::kUncorrected ? "uncorrected C_O'"
                         : m == Method::kRayPlane  ? "corrected, beta by ray_plane"
                                                   : "corrected, beta by centroid (paper)";
    per_sweep[m].style = "linespoints";
    per_sweep[m].color = methodColor(m);
  }
  for (const auto& [mode, g] : in.modes) {
    const size_t n = g.sweeps.size();
    for (size_t j = 0; j < n; ++j) {
      const double x = mode - 0.35 + 0.7 * (static_cast<double>(j) + 0.5) / static_cast<double>(n);
      for (auto& [m, ser] : per_sweep) {
        const auto e = g.sweeps[j].phiErrorRad(m);
        if (!e) continue;
        ser.x.push_back(x);
        ser.y.push_back(*e * kRadToDeg);
      }
    }
  }
  return per_sweep;
}

// The axes of Figs. 9 and 10: phi_error over the modes that were run (a mode not run gets no
// place on the axis), each labelled "mode N".
SeriesPlotOptions phiErrorAxes(const ReportInput& in, const std::string& title,
                               const std::string& x_label) {
  SeriesPlotOptions so;
  so.x_label = x_label;
  so.y_label = "phi_error (deg)";
  if (!in.modes.empty()) {
    so.x_range = PlotRange{in.modes.begin()->first - 0.5, in.modes.rbegin()->first + 0.5};
  }
  for (const auto& [mode, g] : in.modes)
    so.x_tics.push_back({mode, "mode " + std::to_string(mode)});
  so.title = title;
  return so;
}

void phiErrorFigure(const ReportInput& in, Figures* fig) {
  std::map<Method, Series> per_sweep = phiErrorPerSweep(in);
  const SeriesPlotOptions so =
      phiErrorAxes(in, "Fig. 9: phi_error of every sweep, uncorrected and corrected",
                   "scan mode (sweeps of a mode side by side)");
  fig->add("fig9_phi_error.png",
           "Fig. 9: phi_error of every sweep (mode on the x axis): red uncorrected C_O' "
           "(= -phi_true), blue/green corrected by the plate (ray_plane / centroid).",
           [&](const std::string& png) {
             plotSeries(png,
                        {per_sweep[Method::kUncorrected], per_sweep[Method::kRayPlane],
                         per_sweep[Method::kCentroid]},
                        so);
           });
}

void phiErrorCorrectedFigure(const ReportInput& in, Figures* fig) {
  std::map<Method, Series> per_sweep = phiErrorPerSweep(in);
  const SeriesPlotOptions so = phiErrorAxes(in, "Fig. 9 (zoom): phi_error of every corrected sweep",
                                            "scan mode (sweeps of a mode side by side)");
  fig->add("fig9_phi_error_corrected.png",
           "Fig. 9, zoomed on the corrected sweeps: the residual attitude error of each "
           "plate estimator.",
           [&](const std::string& png) {
             plotSeries(png, {per_sweep[Method::kRayPlane], per_sweep[Method::kCentroid]}, so);
           });
}

// --- Fig. 10: max / mean / min of phi_error per mode -------------------------------------

// For each method (or the corrected ones only): its max, mean and min per mode.
std::vector<Series> phiStatsSeries(const ReportInput& in, bool corrected_only) {
  std::vector<Series> out;
  for (Method m : {Method::kUncorrected, Method::kRayPlane, Method::kCentroid}) {
    Series mx, mean, mn;
    for (const auto& [mode, g] : in.modes) {
      const PhiStats st = phiStats(g.sweeps, m);
      if (st.sweeps == 0) continue;
      mx.x.push_back(mode);
      mx.y.push_back(st.max);
      mean.x.push_back(mode);
      mean.y.push_back(st.mean);
      mn.x.push_back(mode);
      mn.y.push_back(st.min);
    }
    const std::string name = methodKey(m);
    mx.title = name + " max";
    mean.title = name + " mean";
    mn.title = name + " min";
    for (Series* ser : {&mx, &mean, &mn}) {
      ser->color = methodColor(m);
      ser->style = ser == &mean ? "linespoints" : "lines";
      if (!corrected_only || m != Method::kUncorrected) out.push_back(*ser);
    }
  }
  return out;
}

void phiStatsFigure(const ReportInput& in, Figures* fig) {
  const std::vector<Series> stats = phiStatsSeries(in, false);
  const SeriesPlotOptions so =
      phiErrorAxes(in, "Fig. 10: max / mean / min of phi_error per mode", "scan mode");
  fig->add("fig10_phi_error_stats.png",
           "Fig. 10: maximum, mean (with points) and minimum phi_error per mode; the band "
           "between max and min is the attitude uncertainty of the mode.",
           [&](const std::string& png) { plotSeries(png, stats, so); });
}

void phiStatsCorrectedFigure(const ReportInput& in, Figures* fig) {
  const std::vector<Series> stats = phiStatsSeries(in, true);
  const SeriesPlotOptions so = phiErrorAxes(
      in, "Fig. 10 (zoom): max / mean / min of phi_error per mode, corrected", "scan mode");
  fig->add("fig10_phi_error_stats_corrected.png",
           "Fig. 10, zoomed on the corrected sweeps (blue ray_plane, green centroid).",
           [&](const std::string& png) { plotSeries(png, stats, so); });
}

// --- Fig. 11: E_map(d) ----------------------------------------------------------------------

// E_map(d) = d tan(phi_error) (mm) over [0, max_range].
Series mapErrorCurve(const EvalSettings& s, double phi_deg, const std::string& title,
                     const std::string& color, const std::string& style) {
  std::vector<double> d;
  for (int i = 0; i <= 200; ++i) d.push_back(s.max_range_m * i / 200.0);
  Series c;
  c.title = title;
  c.color = color;
  c.style = style;
  // A curve with points is drawn at every 10th distance, so the points stay apart.
  const size_t step = style == "lines" ? 1 : 10;
  for (size_t i = 0; i < d.size(); i += step) {
    c.x.push_back(d[i]);
    c.y.push_back(1000.0 * d[i] * std::tan(phi_deg * kDegToRad));
  }
  return c;
}

// The +-limit lines of the E_map standard; only the upper one has a legend entry.
Series mapErrorLimit(const EvalSettings& s, bool upper) {
  const double lim_mm = 1000.0 * s.map_error_limit_m;
  if (upper)
    return {
        "+-" + fixed(lim_mm, 0) + " mm", {0.0, s.max_range_m}, {lim_mm, lim_mm}, "lines", "black"};
  return {"", {0.0, s.max_range_m}, {-lim_mm, -lim_mm}, "lines", "black"};
}

SeriesPlotOptions mapErrorAxes(const EvalSettings& s, const std::string& title,
                               const std::string& y_label) {
  SeriesPlotOptions fo;
  fo.title = title;
  fo.x_label = "distance d (m)";
  fo.y_label = y_label;
  fo.x_range = PlotRange{0.0, s.max_range_m};
  return fo;
}

// E_map for the max/mean/min phi_error of the mode's corrected sweeps, and where each
// estimator's worst sweep leaves the band. Drawn only if a method corrected a sweep.
void mapErrorFigure(int mode, const Group& g, const EvalSettings& s, Figures* fig) {
  const PhiStats r = phiStats(g.sweeps, Method::kRayPlane);
  const PhiStats c = phiStats(g.sweeps, Method::kCentroid);
  if (r.sweeps == 0 && c.sweeps == 0) return;
  const double lim_mm = 1000.0 * s.map_error_limit_m;
  std::vector<Series> ser = {mapErrorLimit(s, true), mapErrorLimit(s, false)};
  if (r.sweeps > 0) {
    const char* color = methodColor(Method::kRayPlane);
    ser.push_back(mapErrorCurve(s, r.max, "ray_plane max", color, "lines"));
    ser.push_back(mapErrorCurve(s, r.mean, "ray_plane mean", color, "linespoints"));
    ser.push_back(mapErrorCurve(s, r.min, "ray_plane min", color, "lines"));
    const double d50 = mapErrorDistance(r.max_abs * kDegToRad, s.map_error_limit_m, s.max_range_m);
    ser.push_back(
        {"ray_plane: |E_map| <= " + fixed(lim_mm, 0) + " mm up to " + fixed(d50, 2) + " m",
         {d50, d50},
         {-lim_mm, lim_mm},
         "linespoints",
         color});
  }
  if (c.sweeps > 0) {
    const char* color = methodColor(Method::kCentroid);
    ser.push_back(mapErrorCurve(s, c.max, "centroid max", color, "lines"));
    ser.push_back(mapErrorCurve(s, c.min, "centroid min", color, "lines"));
    const double d50 = mapErrorDistance(c.max_abs * kDegToRad, s.map_error_limit_m, s.max_range_m);
    ser.push_back({"centroid: up to " + fixed(d50, 2) + " m",
                   {d50, d50},
                   {-lim_mm, lim_mm},
                   "linespoints",
                   color});
  }
  const SeriesPlotOptions fo = mapErrorAxes(
      s, "Fig. 11, mode " + std::to_string(mode) + ": E_map = d tan(phi_error)", "E_map (mm)");
  fig->add("fig11_map_error_mode" + std::to_string(mode) + ".png",
           "Fig. 11, mode " + std::to_string(mode) +
               ": mapping error E_map(d) for the max/mean/min phi_error of the corrected "
               "sweeps; the vertical marks show where it leaves the +-50 mm band.",
           [&](const std::string& png) { plotSeries(png, ser, fo); });
}

// |E_map| of each mode's worst sweep corrected by ray_plane, one colour per mode.
void mapErrorAllFigure(const ReportInput& in, const EvalSettings& s, Figures* fig) {
  static const char* kModeColors[] = {"#e41a1c", "#ff7f00", "#b8a000", "#4daf4a",
                                      "#17becf", "#377eb8", "#984ea3"};
  std::vector<Series> worst_all;
  for (const auto& [mode, g] : in.modes) {
    const PhiStats r = phiStats(g.sweeps, Method::kRayPlane);
    if (r.sweeps == 0) continue;
    worst_all.push_back(mapErrorCurve(s, r.max_abs, "mode " + std::to_string(mode),
                                      kModeColors[(mode - 1 + 7) % 7], "lines"));
  }
  if (worst_all.empty()) return;
  worst_all.insert(worst_all.begin(), mapErrorLimit(s, true));
  const SeriesPlotOptions fo = mapErrorAxes(
      s, "Fig. 11 (all modes): |E_map| of the worst corrected sweep (ray_plane)", "|E_map| (mm)");
  fig->add("fig11_map_error_all.png",
           "Fig. 11, all modes: |E_map(d)| of each mode's worst corrected sweep (ray_plane); "
           "a curve under the black line stays within 50 mm.",
           [&](const std::string& png) { plotSeries(png, worst_all, fo); });
}

// --- Appendix B (Fig. A2): wall deviations ------------------------------------------------

void wallDeviationsFigure(int mode, const Group& g, const EvalSettings& s, Figures* fig) {
  Series h;
  h.title = "mode " + std::to_string(mode) + ": " + g.deviations.rmsLabel() +
            (g.deviations.count > 0
                 ? ", " + fixed(100.0 * g.deviations.shareWithin(), 2) + " % within +-40 mm"
                 : std::string(" (no walls found)"));
  h.style = "boxes";
  h.color = "#4477aa";
  for (size_t i = 0; i < g.deviations.bins.size(); ++i) {
    h.x.push_back(g.deviations.binCenterMm(i));
    h.y.push_back(static_cast<double>(g.deviations.bins[i]));
  }
  double top = 0;
  for (double y : h.y) top = std::max(top, y);
  const Series lo{"+-40 mm", {-s.within_mm, -s.within_mm}, {0.0, top}, "lines", "red"};
  const Series hi{"", {s.within_mm, s.within_mm}, {0.0, top}, "lines", "red"};
  SeriesPlotOptions fo;
  fo.title = "Appendix B, mode " + std::to_string(mode) +
             ": deviations of wall points from their planes (4 walls, all sweeps)";
  fo.x_label = "deviation (mm)";
  fo.y_label = "points";
  fig->add("figA2_wall_deviations_mode" + std::to_string(mode) + ".png",
           "Appendix B, mode " + std::to_string(mode) +
               ": histogram of the signed distances of wall points to their fitted planes; "
               "a narrow, normal-looking peak inside +-40 mm means the cloud's shape is right.",
           [&](const std::string& png) {
             plotSeries(png, {h, lo, hi}, fo);
           });
}

// --- the alpha calibration (Algorithm A1) ---------------------------------------------------

// The calibrations that were done, with their method.
std::vector<std::pair<const AlphaCalibration*, Method>> alphaCalibrations(const ReportInput& in) {
  std::vector<std::pair<const AlphaCalibration*, Method>> out;
  if (in.alpha.done) out.emplace_back(&in.alpha, Method::kRayPlane);
  if (in.alpha_centroid.done) out.emplace_back(&in.alpha_centroid, Method::kCentroid);
  return out;
}

void alphaCostFigure(const ReportInput& in, Figures* fig) {
  std::vector<Series> cost;
  for (const auto& [a, m] : alphaCalibrations(in)) {
    Series c{std::string("F_cost, ") + methodKey(m), {}, {}, "linespoints", methodColor(m)};
    for (const auto& it : a->lm.history) {
      c.x.push_back(it.k);
      c.y.push_back(std::max(it.cost, 1e-30));
    }
    cost.push_back(c);
  }
  SeriesPlotOptions fo;
  fo.x_label = "LM iteration k";
  fo.title = "Alpha calibration (Algorithm A1): F_cost per iteration";
  fo.y_label = "F_cost (Eq. 20)";
  fo.log_y = true;
  fig->add("fig_alpha_calibration_cost.png",
           "Alpha calibration (Algorithm A1): the cost F_cost of Eq. 20 at each LM iteration.",
           [&](const std::string& png) { plotSeries(png, cost, fo); });
}

void alphaFigure(const ReportInput& in, Figures* fig) {
  std::vector<Series> alpha;
  for (const auto& [a, m] : alphaCalibrations(in)) {
    Series al{std::string("alpha, ") + methodKey(m), {}, {}, "linespoints", methodColor(m)};
    for (const auto& it : a->lm.history) {
      al.x.push_back(it.k);
      al.y.push_back(it.alpha_rad * kRadToDeg);
    }
    alpha.push_back(al);
  }
  if (in.alpha_true_rad && !alpha.empty() && !alpha.front().x.empty()) {
    double k_max = 1;
    for (const auto& ser : alpha) k_max = std::max(k_max, ser.x.back());
    alpha.push_back({"true alpha (simulator)",
                     {0.0, k_max},
                     {*in.alpha_true_rad * kRadToDeg, *in.alpha_true_rad * kRadToDeg},
                     "lines",
                     "black"});
  }
  SeriesPlotOptions fo;
  fo.x_label = "LM iteration k";
  fo.title = "Alpha calibration (Algorithm A1): alpha per iteration";
  fo.y_label = "alpha (deg)";
  fo.log_y = false;
  fig->add("fig_alpha_calibration_alpha.png",
           "Alpha calibration: the plate angle alpha at each LM iteration, from alpha_0 "
           "toward the calibrated value (black: the simulator's true alpha, when known).",
           [&](const std::string& png) { plotSeries(png, alpha, fo); });
}

// --- Fig. 1: shape error of the naive action sequence ---------------------------------------

void naiveTopViewFigure(const Group& nv, const EvalSettings& s, Figures* fig) {
  fig->add("fig1_naive_top_view.png",
           "Fig. 1: top view of one mode-1 sweep taken with the NAIVE action sequence "
           "(lidar and motor start together): the motor's ramps bend the walls (shape error); "
           "the sweep is published uncorrected.",
           [&](const std::string& png) {
             PlotOptions po;
             po.title = "Mode 1, naive action sequence: sweep " +
                        std::to_string(nv.sweeps.front().id) + " (C_O', shape error)";
             po.z_band_m = PlotRange{s.top_view_z_min_m, s.top_view_z_max_m};
             // Not overlaid with an improved sweep: the naive cloud's attitude is arbitrary.
             const std::vector<Eigen::Vector3f> first(
                 nv.top_Op.begin(),
                 nv.top_Op.begin() + static_cast<std::ptrdiff_t>(nv.first_sweep_top_points));
             plotTopView(png, {{"naive sequence, C_O'", "red", first}}, po);
           });
}

// The deviation histogram as shares of the wall points (%).
Series deviationShares(const DeviationStats& d, const std::string& label,
                       const std::string& color) {
  Series h{
      label + ": " + d.rmsLabel() + ", " + fixed(100 * d.shareWithin(), 1) + " % within +-40 mm",
      {},
      {},
      "lines",
      color};
  for (size_t i = 0; i < d.bins.size(); ++i) {
    h.x.push_back(d.binCenterMm(i));
    h.y.push_back(d.count > 0 ? 100.0 * static_cast<double>(d.bins[i]) / d.count : 0.0);
  }
  return h;
}

// Mode 1's wall deviations, naive against improved sequence.
void shapeDeviationsFigure(const ReportInput& in, Figures* fig) {
  const Group& nv = *in.naive;
  const auto improved = in.modes.find(1);
  std::vector<Series> hs;
  if (nv.deviations.count > 0) hs.push_back(deviationShares(nv.deviations, "naive", "red"));
  if (improved != in.modes.end() && improved->second.deviations.count > 0) {
    hs.push_back(deviationShares(improved->second.deviations, "improved", "blue"));
  }
  if (hs.empty()) return;
  SeriesPlotOptions fo;
  fo.title = "Fig. 1 / Appendix B, mode 1: wall deviations, naive vs improved action sequence";
  fo.x_label = "deviation (mm)";
  fo.y_label = "share of wall points (%)";
  fig->add("fig1_shape_deviations.png",
           "Shape error: wall-point deviations in mode 1, naive (red) vs improved (blue) "
           "action sequence; the naive sequence's ramps spread the walls.",
           [&](const std::string& png) { plotSeries(png, hs, fo); });
}

// --- 3D pictures: one sweep of the densest mode and its map, as the replay draws them ------

void views3dFigures(const ReportInput& in, Figures* fig) {
  const auto densest = std::max_element(in.modes.begin(), in.modes.end(), [](auto& a, auto& b) {
    return a.second.first_sweep_O.size() < b.second.first_sweep_O.size();
  });
  if (densest == in.modes.end() || densest->second.first_sweep_O.empty()) return;
  const int mode = densest->first;
  const std::vector<Eigen::Vector3f>& cloud = densest->second.first_sweep_O;
  const std::string what = "rig A eval, mode " + std::to_string(mode) + ", first sweep";
  const ZBand band = wallBand(cloud);  // the room's ceiling would hide it from above
  fig->add("cloud_3d.png",
           "The first mode-" + std::to_string(mode) +
               " sweep (C_O) in perspective, shaded by height, the ceiling left out: walls "
               "should stand straight and meet at the corners, the floor lie flat.",
           [&](const std::string& png) { drawCloud3d(png, what, "O", cloud, band); });
  fig->add("map_3d.png",
           "The same sweep's occupied voxels, as the mapper inserts it (rays from the axis), "
           "in perspective.",
           [&](const std::string& png) {
             OccupancyMap map(in.mapper);
             map.insertCloud(cloud, Eigen::Vector3f::Zero());  // rig A: the lidar on the axis
             drawMap3d(png, what, map.occupiedCentres(), in.mapper.resolution_m, band);
           });
}

}  // namespace

void drawFigures(const ReportInput& in, const EvalSettings& s, bool has_truth, Figures* fig) {
  for (const auto& [mode, g] : in.modes) {
    if (!g.top_O.empty()) topViewFigure(mode, g, s, fig);
  }
  views3dFigures(in, fig);
  if (has_truth) {
    phiErrorFigure(in, fig);
    phiErrorCorrectedFigure(in, fig);
    phiStatsFigure(in, fig);
    phiStatsCorrectedFigure(in, fig);
    for (const auto& [mode, g] : in.modes) mapErrorFigure(mode, g, s, fig);
    mapErrorAllFigure(in, s, fig);
  }
  for (const auto& [mode, g] : in.modes) {
    if (g.deviations.count > 0) wallDeviationsFigure(mode, g, s, fig);
  }
  if (in.alpha.done || in.alpha_centroid.done) {
    alphaCostFigure(in, fig);
    alphaFigure(in, fig);
  }
  if (in.naive && !in.naive->sweeps.empty()) {
    naiveTopViewFigure(*in.naive, s, fig);
    shapeDeviationsFigure(in, fig);
  }
}

}  // namespace sweepmap::eval
