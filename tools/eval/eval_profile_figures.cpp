#include "tools/eval/eval_profile_figures.hpp"

#include <cmath>
#include <stdexcept>

#include "mapping/plot.hpp"
#include "tools/eval/common.hpp"
#include "tools/offline/calibrate_axis_offset.hpp"

namespace sweepmap::eval {
namespace {

// Top view of the piece's frame (u across, v along the scan), coloured by depth below the
// top face.
void drawCloud(const std::string& png, const PieceMeasurement& m) {
  Layer top{"top face", "#b0b0b0", {}},
      walls{"walls (0.5 mm below the top to 19 mm)", "#d62728", {}},
      bottoms{"groove bottoms (19 mm and deeper)", "#1f77b4", {}};
  for (const Eigen::Vector3f& p : m.cloud) {
    const Eigen::Vector3f q(p.y(), p.x(), 0.0f);  // scan direction to the right
    if (p.z() > -0.5f) {
      top.points.push_back(q);
    } else if (p.z() > -19.0f) {
      walls.points.push_back(q);
    } else {
      bottoms.points.push_back(q);
    }
  }
  PlotOptions o;
  o.title = "Test piece, scan 1, assembled with our calibration (Zhao 2021 Fig. 9)";
  o.x_label = "v: along the scan [mm]";
  o.y_label = "u: along the laser line [mm]";
  o.point_size = 0.15;
  o.height_px = 700;
  plotTopView(png, {top, bottoms, walls}, o);  // walls last: on top
}

// Mean error [%] per feature and setting, with the standard deviation as the bar.
void drawErrors(const std::string& png, const ProfileEvaluation& ev, bool zoom_on_ours) {
  const char* colours[] = {"#2ca02c", "#1f77b4", "#d62728", "#ff7f0e"};
  std::vector<Series> series;
  SeriesPlotOptions o;
  for (size_t s = 0; s < ev.settings.size(); ++s) {
    const ProfileSetting& set = ev.settings[s];
    if (zoom_on_ours && set.name != "ours" && set.name != "grid") continue;
    Series ser{set.label, {}, {}, "yerrorbars", colours[s % 4], {}};  // y_err last
    for (int k = 0; k < kPieceFeatureCount; ++k) {
      const Stats st = errorPctStats(set, ev.piece, k);
      if (st.count == 0) continue;
      ser.x.push_back(k + 0.12 * (static_cast<double>(s) - 1.5));
      ser.y.push_back(st.mean);
      ser.y_err.push_back(st.std);
    }
    series.push_back(ser);
  }
  for (const double bound : {0.1, -0.1}) {
    series.push_back({bound > 0 ? "+-0.1 % (sweepmap's error bound for a calibrated rig)" : "",
                      {-0.5, 6.5},
                      {bound, bound},
                      "lines",
                      "#7f7f7f",
                      {}});
  }
  for (int k = 0; k < kPieceFeatureCount; ++k) o.x_tics.push_back({k, kPieceFeatures[k]});
  o.title = zoom_on_ours
                ? "Feature errors: ours and the paper's grid (mean +- std over the scans)"
                : "Feature errors per setting (mean +- std over the scans; Zhao 2021 Table 2)";
  o.y_label = "error [%]";
  o.x_range = PlotRange{-0.5, 6.5};
  o.width_px = 1200;
  plotSeries(png, series, o);
}

}  // namespace

void drawProfileFigures(const ProfileEvaluation& ev, Figures* figures) {
  figures->add("s_surface.png",
               "S(M, N): the mean plane RMSE of the paper's grid search over its interval, 1 mm "
               "steps (Zhao 2021 Fig. 6), its minimum marked.",
               [&](const std::string& png) {
                 const std::string why = drawAxisOffsetSurface(png, ev.grid);
                 if (!why.empty()) throw std::runtime_error(why);
               });
  figures->add("test_piece_cloud.png",
               "The first test-piece scan assembled with our calibration, seen from above in "
               "the piece's frame: top face, groove walls, groove bottoms.",
               [&](const std::string& png) { drawCloud(png, ev.example); });
  figures->add("feature_errors.png",
               "Each feature's error per setting, mean and standard deviation over the scans: "
               "the wrong settings move the sizes along the scan (diameters, rectangle length).",
               [&](const std::string& png) { drawErrors(png, ev, false); });
  figures->add("feature_errors_ours.png",
               "The same for ours and the paper's grid only, with the +-0.1 % bound.",
               [&](const std::string& png) { drawErrors(png, ev, true); });
}

}  // namespace sweepmap::eval
