// PNG pictures drawn by the `gnuplot` binary (Debian package gnuplot-nox, terminal
// pngcairo). The data go to temporary binary files next to the PNG, the commands to a
// script file (no shell is involved; paths and titles are quoted for gnuplot), and the
// PNG is written as `png_path + ".tmp"` and renamed, so a half-drawn picture is never seen.
// Every function throws std::runtime_error (with gnuplot's exit status and its last error
// lines) if gnuplot is missing or fails, and std::invalid_argument for bad arguments.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sweepmap {

// True if an executable `gnuplot` is on PATH.
bool gnuplotAvailable();

struct PlotRange {
  double min = 0.0;
  double max = 0.0;
};

// One set of points in a top view. Coordinates in metres, in the caller's frame; the view
// looks down the z axis (x to the right, y up).
struct Layer {
  std::string title;  // legend entry; empty: no entry
  std::string color;  // gnuplot colour: "red", "#1f77b4"; empty: next default
  std::vector<Eigen::Vector3f> points;
  bool by_height = false;  // each point coloured by its z (a colour bar), not by `color`
};

struct PlotOptions {
  std::string title;
  std::optional<PlotRange> x_range_m;  // unset: autoscale
  std::optional<PlotRange> y_range_m;
  std::optional<PlotRange> z_band_m;  // set: draw only points with min <= z <= max
  double point_size = 0.3;            // gnuplot pointsize of a filled circle
  std::string x_label = "x [m]";      // side views pass their own axes
  std::string y_label = "y [m]";
  int width_px = 1200;
  int height_px = 900;
  // Larger layers are subsampled with a fixed stride. 50 000 filled circles of 0.3 already
  // cover a 1200 x 900 picture; drawing 200 000 took most of a replay's time.
  size_t max_points_per_layer = 50000;
};

// Top view (x-y) of the layers, drawn in order (the last on top), equal axis scaling.
void plotTopView(const std::string& png_path, const std::vector<Layer>& layers,
                 const PlotOptions& options);

// A perspective view of the layers (3D, equal axes), each point shaded by its height: the
// report's picture of a whole cloud or map. Layers with a `color` and by_height false are drawn
// in that colour (a path). Subsampled with a fixed stride to max_points_per_layer.
struct PerspectiveOptions {
  std::string title;
  double rot_x_deg = 55.0;  // gnuplot `set view rot_x, rot_z`: the camera's tilt from above
  double rot_z_deg = 35.0;  // and its turn about z
  double point_size = 0.25;
  size_t max_points_per_layer = 60000;
  int width_px = 1200;
  int height_px = 900;
};

void plotPerspective(const std::string& png_path, const std::vector<Layer>& layers,
                     const PerspectiveOptions& options);

// A generic x-y series, for error curves and histograms.
struct Series {
  std::string title;
  std::vector<double> x, y;     // same length
  std::string style = "lines";  // "lines" | "points" | "linespoints" | "boxes" | "yerrorbars"
  std::string color;            // empty: next default colour
  std::vector<double> y_err{};  // "yerrorbars": the bar's half length at each point
};

struct SeriesPlotOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::optional<PlotRange> x_range;
  std::optional<PlotRange> y_range;
  bool log_y = false;
  std::vector<std::pair<double, std::string>> x_tics;  // labelled ticks instead of numbers
  int width_px = 1000;
  int height_px = 700;
};

void plotSeries(const std::string& png_path, const std::vector<Series>& series,
                const SeriesPlotOptions& options);

// A surface z(x_i, y_j) over a grid, drawn in 3D with a colour map (pm3d) and the point
// `marker` (if set) on it, as Zhao 2021 Fig. 6 draws S(M, N).
struct SurfacePlotOptions {
  std::string title;
  std::string x_label, y_label, z_label;
  std::optional<Eigen::Vector3d> marker;  // drawn as a labelled point
  std::string marker_title;
  int width_px = 1000;
  int height_px = 800;
};

// z[i * y.size() + j] is the value at (x[i], y[j]); non-finite values are left out.
void plotSurface(const std::string& png_path, const std::vector<double>& x,
                 const std::vector<double>& y, const std::vector<double>& z,
                 const SurfacePlotOptions& options);

}  // namespace sweepmap
