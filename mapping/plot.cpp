#include "mapping/plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>  // cross
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <locale>
#include <sstream>
#include <stdexcept>

#include "core/atomic_file.hpp"

extern char** environ;

namespace sweepmap {
namespace {

// A gnuplot single-quoted string: no escapes inside, except '' for a quote. Line breaks
// would end the command, so they are refused in paths and flattened in titles.
std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'') {
      out += "''";
    } else if (c == '\n' || c == '\r') {
      out += ' ';
    } else {
      out += c;
    }
  }
  return out + "'";
}

void checkPath(const std::string& path) {
  if (path.empty()) throw std::invalid_argument("plot: empty output path");
  if (path.find_first_of(std::string("\n\r\0", 3)) != std::string::npos) {
    throw std::invalid_argument("plot: output path contains a line break or NUL: " + path);
  }
}

// Files removed when the plot is done, whatever happens.
class TempFiles {
 public:
  explicit TempFiles(std::string base) : base_(std::move(base)) {}
  ~TempFiles() {
    for (const auto& p : paths_) std::remove(p.c_str());
  }
  TempFiles(const TempFiles&) = delete;
  TempFiles& operator=(const TempFiles&) = delete;
  std::string make(const std::string& suffix) {
    paths_.push_back(base_ + suffix);
    return paths_.back();
  }

 private:
  std::string base_;
  std::vector<std::string> paths_;
};

template <typename T>
void writeRaw(const std::string& path, const std::vector<T>& values) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(values.data()),
            static_cast<std::streamsize>(values.size() * sizeof(T)));
  out.close();
  if (!out) throw std::runtime_error("plot: cannot write temporary file " + path);
}

std::string readTail(const std::string& path, size_t max_chars) {
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.size() > max_chars) text = "..." + text.substr(text.size() - max_chars);
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  return text;
}

// Runs `gnuplot script` without a shell; stdin and stdout are /dev/null, stderr goes to
// `stderr_path`. Throws with the exit status and gnuplot's last words on failure.
void runGnuplot(const std::string& script_path, const std::string& stderr_path) {
  // A relative path starting with '-' would be read as an option.
  const std::string script_arg = script_path[0] == '/' ? script_path : "./" + script_path;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  std::vector<char*> argv = {const_cast<char*>("gnuplot"), const_cast<char*>(script_arg.c_str()),
                             nullptr};
  pid_t pid = 0;
  const int spawn_rc = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawn_rc != 0) {
    throw std::runtime_error(std::string("plot: cannot run gnuplot: ") + std::strerror(spawn_rc));
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error("plot: waitpid on gnuplot failed");
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  std::ostringstream msg;
  if (WIFEXITED(status)) {
    msg << "plot: gnuplot exited with status " << WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    msg << "plot: gnuplot killed by signal " << WTERMSIG(status);
  } else {
    msg << "plot: gnuplot failed (wait status " << status << ")";
  }
  const std::string err = readTail(stderr_path, 600);
  if (!err.empty()) msg << ": " << err;
  throw std::runtime_error(msg.str());
}

// Number formatting independent of the global locale.
std::ostringstream scriptStream() {
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s.precision(10);
  return s;
}

void writeHeader(std::ostream& s, const std::string& png_tmp, int width_px, int height_px,
                 const std::string& title) {
  if (width_px <= 0 || height_px <= 0) throw std::invalid_argument("plot: bad picture size");
  // noenhanced: '_' and '^' in titles are plain characters, not sub/superscripts.
  s << "set terminal pngcairo size " << width_px << "," << height_px << " noenhanced\n"
    << "set output " << quoted(png_tmp) << "\n";
  if (!title.empty()) s << "set title " << quoted(title) << "\n";
  s << "set grid\n";
}

void writeAxisLabels(std::ostream& s, const std::string& x_label, const std::string& y_label) {
  if (!x_label.empty()) s << "set xlabel " << quoted(x_label) << "\n";
  if (!y_label.empty()) s << "set ylabel " << quoted(y_label) << "\n";
}

void writeRange(std::ostream& s, const char* axis, const std::optional<PlotRange>& r) {
  if (!r) return;
  if (!(r->min < r->max)) throw std::invalid_argument(std::string("plot: empty ") + axis + "range");
  s << "set " << axis << "range [" << r->min << ":" << r->max << "]\n";
}

// Draws the script into png_path + ".tmp" and renames it over png_path.
void render(const std::string& png_path, const std::string& script, TempFiles& temps,
            const std::string& png_tmp) {
  const std::string script_path = temps.make(".gp.tmp");
  const std::string stderr_path = temps.make(".gperr.tmp");
  {
    std::ofstream out(script_path, std::ios::trunc);
    out << script;
    out.close();
    if (!out) throw std::runtime_error("plot: cannot write temporary file " + script_path);
  }
  try {
    runGnuplot(script_path, stderr_path);
  } catch (...) {
    std::remove(png_tmp.c_str());
    throw;
  }
  struct stat st {};
  if (::stat(png_tmp.c_str(), &st) != 0 || st.st_size == 0) {
    std::remove(png_tmp.c_str());
    throw std::runtime_error("plot: gnuplot wrote no picture for " + png_path);
  }
  commitTmpFile(png_tmp, png_path);
}

// "plot A, B, ..." (one clause per line).
void writePlotCommand(std::ostringstream& s, const std::vector<std::string>& plots) {
  s << "plot ";
  for (size_t i = 0; i < plots.size(); ++i) s << (i ? ", \\\n     " : "") << plots[i];
  s << "\n";
}

}  // namespace

bool gnuplotAvailable() {
  const char* path_env = std::getenv("PATH");
  std::string path = path_env ? path_env : "/usr/bin:/bin";
  size_t start = 0;
  while (start <= path.size()) {
    size_t end = path.find(':', start);
    if (end == std::string::npos) end = path.size();
    std::string dir = path.substr(start, end - start);
    if (dir.empty()) dir = ".";
    if (::access((dir + "/gnuplot").c_str(), X_OK) == 0) return true;
    start = end + 1;
  }
  return false;
}

namespace {

// The points of `layer` to draw: finite, inside `z_band` if set, at most `max_points` with a
// fixed stride (the same input always gives the same picture).
std::vector<Eigen::Vector3f> pointsToDraw(const Layer& layer,
                                          const std::optional<PlotRange>& z_band,
                                          size_t max_points) {
  std::vector<const Eigen::Vector3f*> kept;
  kept.reserve(layer.points.size());
  for (const Eigen::Vector3f& p : layer.points) {
    if (!p.allFinite()) continue;
    if (z_band && (p.z() < z_band->min || p.z() > z_band->max)) continue;
    kept.push_back(&p);
  }
  const size_t n = kept.size();
  const size_t m = std::min(n, max_points);
  std::vector<Eigen::Vector3f> out;
  out.reserve(m);
  for (size_t k = 0; k < m; ++k) out.push_back(*kept[static_cast<size_t>((uint64_t{k} * n) / m)]);
  return out;
}

// The 2nd and 98th percentile of the points' z: a colour range that outliers do not flatten.
std::optional<PlotRange> heightRange(const std::vector<Eigen::Vector3f>& points) {
  if (points.empty()) return std::nullopt;
  std::vector<float> z;
  z.reserve(points.size());
  for (const auto& p : points) z.push_back(p.z());
  const size_t lo = z.size() * 2 / 100, hi = (z.size() - 1) * 98 / 100;
  std::nth_element(z.begin(), z.begin() + lo, z.end());
  const float zmin = z[lo];
  std::nth_element(z.begin(), z.begin() + hi, z.end());
  const float zmax = z[hi];
  return PlotRange{zmin, zmax > zmin ? zmax : zmin + 0.01};
}

// The colour of a layer drawn in one colour: its own, else the `index`-th default.
std::string layerColour(const Layer& layer, size_t index) {
  return layer.color.empty() ? "lt " + std::to_string(index + 1) : "rgb " + quoted(layer.color);
}

// The palette of height-coloured layers and its colour bar.
void writeHeightPalette(std::ostringstream& s, const PlotRange& z) {
  s << "set palette rgbformulae 33,13,10\nset cbrange [" << z.min << ":" << z.max << "]\n"
    << "set cblabel 'height z [m]'\n";
}

// A legend entry with a marker large enough to see (the layer itself is drawn without one:
// its points are too small to show their colour in the key).
std::string legendEntry(const Layer& layer, size_t index) {
  const std::string colour = layer.by_height ? "rgb 'gray40'" : layerColour(layer, index);
  return "NaN with points pt 7 ps 2 lc " + colour + " title " +
         quoted(layer.by_height ? layer.title + " (colour: height)" : layer.title);
}

}  // namespace

void plotTopView(const std::string& png_path, const std::vector<Layer>& layers,
                 const PlotOptions& options) {
  checkPath(png_path);
  if (!(options.point_size > 0.0)) throw std::invalid_argument("plotTopView: point_size <= 0");
  if (options.max_points_per_layer == 0) {
    throw std::invalid_argument("plotTopView: max_points_per_layer is 0");
  }
  TempFiles temps(png_path);
  const std::string png_tmp = tmpPathFor(png_path);

  std::ostringstream s = scriptStream();
  writeHeader(s, png_tmp, options.width_px, options.height_px, options.title);
  s << "set xlabel " << quoted(options.x_label) << "\nset ylabel " << quoted(options.y_label)
    << "\n"
    << "set size ratio -1\n"  // one metre is as long on both axes
    << "set key below\n";     // beside the plot it took a third of the width
  writeRange(s, "x", options.x_range_m);
  writeRange(s, "y", options.y_range_m);

  std::vector<std::string> plots, legend;
  std::vector<std::vector<Eigen::Vector3f>> drawn;
  std::vector<Eigen::Vector3f> coloured;  // every height-coloured point, for the colour range
  for (const Layer& layer : layers) {
    drawn.push_back(pointsToDraw(layer, options.z_band_m, options.max_points_per_layer));
    if (layer.by_height) coloured.insert(coloured.end(), drawn.back().begin(), drawn.back().end());
  }
  if (const auto z = options.z_band_m ? options.z_band_m : heightRange(coloured);
      z && !coloured.empty()) {
    writeHeightPalette(s, *z);
  }
  for (size_t l = 0; l < layers.size(); ++l) {
    const Layer& layer = layers[l];
    if (drawn[l].empty()) continue;  // gnuplot refuses an empty data file
    std::vector<float> xyz;
    xyz.reserve(3 * drawn[l].size());
    for (const Eigen::Vector3f& p : drawn[l]) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
    const std::string data_path = temps.make(".layer" + std::to_string(l) + ".tmp");
    writeRaw(data_path, xyz);
    std::ostringstream c = scriptStream();
    c << quoted(data_path) << " binary format='%float32%float32%float32' using 1:2"
      << (layer.by_height ? ":3" : "") << " with points pt 7 ps " << options.point_size << " lc "
      << (layer.by_height ? "palette" : layerColour(layer, l)) << " notitle";
    plots.push_back(c.str());
    if (!layer.title.empty()) legend.push_back(legendEntry(layer, l));
  }
  plots.insert(plots.end(), legend.begin(), legend.end());
  if (drawn.empty() ||
      std::all_of(drawn.begin(), drawn.end(), [](const auto& d) { return d.empty(); })) {
    plots.clear();
    // Nothing to draw: an empty frame (autoscale has nothing to work with, so fix ranges).
    if (!options.x_range_m) s << "set xrange [-1:1]\n";
    if (!options.y_range_m) s << "set yrange [-1:1]\n";
    plots.push_back("NaN notitle");
  }
  writePlotCommand(s, plots);
  render(png_path, s.str(), temps, png_tmp);
}

namespace {

// A pinhole camera looking at the middle of the points from `rot_x` degrees off vertical and
// `rot_z` degrees round z, far enough (2.2 bounding radii) to see them all.
struct Camera {
  Eigen::Vector3f eye, forward, right, up;
  float distance = 1.0f;
};

Camera cameraFor(const std::vector<std::vector<Eigen::Vector3f>>& drawn,
                 const PerspectiveOptions& o) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo;
  for (const auto& layer : drawn) {
    for (const auto& p : layer) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  const Eigen::Vector3f centre = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * (hi - lo).norm(), 0.01f);
  const float tilt = static_cast<float>(o.rot_x_deg * M_PI / 180.0);
  const float az = static_cast<float>(o.rot_z_deg * M_PI / 180.0);
  const Eigen::Vector3f to_eye(std::sin(tilt) * std::sin(az), -std::sin(tilt) * std::cos(az),
                               std::cos(tilt));
  Camera c;
  c.distance = 2.2f * radius;
  c.eye = centre + c.distance * to_eye;
  c.forward = -to_eye;
  c.right = c.forward.cross(Eigen::Vector3f::UnitZ());
  if (c.right.norm() < 1e-6f) c.right = Eigen::Vector3f::UnitX();
  c.right.normalize();
  c.up = c.right.cross(c.forward);
  return c;
}

// The layer's points seen by the camera, far ones first (the near ones are drawn over them):
// x, y on the image plane, the point size (shrinking with distance) and the height z.
std::vector<float> project(const std::vector<Eigen::Vector3f>& points, const Camera& c,
                           double point_size) {
  std::vector<std::pair<float, size_t>> order;  // depth, index
  order.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const float depth = (points[i] - c.eye).dot(c.forward);
    if (depth > 0.05f * c.distance) order.push_back({depth, i});
  }
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && a.second < b.second);
  });
  std::vector<float> out;
  out.reserve(4 * order.size());
  for (const auto& [depth, i] : order) {
    const Eigen::Vector3f v = points[i] - c.eye;
    out.insert(out.end(), {v.dot(c.right) / depth, v.dot(c.up) / depth,
                           static_cast<float>(point_size) * c.distance / depth, points[i].z()});
  }
  return out;
}

}  // namespace

void plotPerspective(const std::string& png_path, const std::vector<Layer>& layers,
                     const PerspectiveOptions& options) {
  checkPath(png_path);
  TempFiles temps(png_path);
  const std::string png_tmp = tmpPathFor(png_path);
  std::ostringstream s = scriptStream();
  writeHeader(s, png_tmp, options.width_px, options.height_px, options.title);
  s << "unset grid\nunset xtics\nunset ytics\nunset border\nset size ratio -1\n"
    << "set key below\n";
  std::vector<std::vector<Eigen::Vector3f>> drawn;
  std::vector<Eigen::Vector3f> coloured;
  for (const Layer& layer : layers) {
    drawn.push_back(pointsToDraw(layer, std::nullopt, options.max_points_per_layer));
    if (layer.by_height) coloured.insert(coloured.end(), drawn.back().begin(), drawn.back().end());
  }
  if (const auto z = heightRange(coloured)) writeHeightPalette(s, *z);
  const Camera camera = cameraFor(drawn, options);
  std::vector<std::string> plots, legend;
  for (size_t l = 0; l < layers.size(); ++l) {
    const std::vector<float> data = project(drawn[l], camera, options.point_size);
    if (data.empty()) continue;
    const std::string data_path = temps.make(".view" + std::to_string(l) + ".tmp");
    writeRaw(data_path, data);
    plots.push_back(
        quoted(data_path) + " binary format='%float32%float32%float32%float32' using 1:2:3" +
        (layers[l].by_height ? ":4 with points pt 7 ps variable lc palette"
                             : " with points pt 7 ps variable lc " + layerColour(layers[l], l)) +
        " notitle");
    // A height-shaded layer is explained by the colour bar; a coloured one (a path) by the key.
    if (!layers[l].title.empty() && !layers[l].by_height) {
      legend.push_back(legendEntry(layers[l], l));
    }
  }
  plots.insert(plots.end(), legend.begin(), legend.end());
  if (legend.empty()) s << "unset key\n";
  if (plots.empty()) {
    s << "set xrange [-1:1]\nset yrange [-1:1]\n";
    plots.push_back("NaN notitle");
  }
  writePlotCommand(s, plots);
  render(png_path, s.str(), temps, png_tmp);
}

namespace {

// The axes of a series plot: labels, log scale, labelled ticks, ranges, box fill.
void writeSeriesAxes(std::ostringstream& s, const SeriesPlotOptions& options) {
  writeAxisLabels(s, options.x_label, options.y_label);
  if (options.log_y) s << "set logscale y\n";
  if (!options.x_tics.empty()) {
    s << "set xtics (";
    for (size_t k = 0; k < options.x_tics.size(); ++k) {
      s << (k ? ", " : "") << quoted(options.x_tics[k].second) << " " << options.x_tics[k].first;
    }
    s << ")\n";
  }
  // Boxes: see-through, so that a series behind stays visible.
  s << "set style fill transparent solid 0.5 border -1\n";
  writeRange(s, "x", options.x_range);
  writeRange(s, "y", options.y_range);
}

// A box is as wide as the gap to its neighbour: keep the outer half-boxes in the autoscaled
// x range, and the bars' base (y = 0) in the y range.
void writeRoomForBoxes(std::ostringstream& s, const std::vector<Series>& series,
                       const SeriesPlotOptions& options) {
  double half_box = 0.0;
  for (const Series& ser : series) {
    if (ser.style != "boxes" || ser.x.size() < 2) continue;
    std::vector<double> xs = ser.x;
    std::sort(xs.begin(), xs.end());
    double gap = 0.0;
    for (size_t k = 1; k < xs.size(); ++k) {
      const double d = xs[k] - xs[k - 1];
      if (d > 0.0 && (gap == 0.0 || d < gap)) gap = d;
    }
    half_box = std::max(half_box, gap / 2);
  }
  const bool has_boxes = std::any_of(series.begin(), series.end(),
                                     [](const Series& ser) { return ser.style == "boxes"; });
  if (!options.x_range && half_box > 0.0) {
    s << "set offsets " << half_box << ", " << half_box << ", 0, 0\n";
  }
  if (!options.y_range && has_boxes && !options.log_y) s << "set yrange [*<0:0<*]\n";
}

// The series' gnuplot `with` clause; throws std::invalid_argument for an unknown style or
// arrays of different lengths.
std::string seriesStyle(const Series& ser) {
  if (ser.x.size() != ser.y.size()) {
    throw std::invalid_argument("plotSeries: x and y of '" + ser.title + "' differ in length");
  }
  if (ser.style == "lines" || ser.style == "boxes") return ser.style;
  if (ser.style == "points") return "points pt 7 ps 0.5";
  if (ser.style == "linespoints") return "linespoints pt 7 ps 0.5";
  if (ser.style == "yerrorbars") {
    if (ser.y_err.size() != ser.y.size()) {
      throw std::invalid_argument("plotSeries: y and y_err of '" + ser.title +
                                  "' differ in length");
    }
    return "yerrorbars pt 7 ps 1";
  }
  throw std::invalid_argument("plotSeries: unknown style '" + ser.style + "'");
}

// Writes the series' points to a temporary binary file; returns its plot clause.
std::string seriesClause(const Series& ser, const std::string& with, size_t index,
                         TempFiles& temps) {
  const bool bars = ser.style == "yerrorbars";
  std::vector<double> xy;
  xy.reserve((bars ? 3 : 2) * ser.x.size());
  for (size_t k = 0; k < ser.x.size(); ++k) {
    xy.push_back(ser.x[k]);
    xy.push_back(ser.y[k]);
    if (bars) xy.push_back(ser.y_err[k]);
  }
  const std::string data_path = temps.make(".series" + std::to_string(index) + ".tmp");
  writeRaw(data_path, xy);
  std::ostringstream c = scriptStream();
  c << quoted(data_path)
    << (bars ? " binary format='%float64%float64%float64' using 1:2:3 with "
             : " binary format='%float64%float64' using 1:2 with ")
    << with;
  if (!ser.color.empty()) c << " lc rgb " << quoted(ser.color);
  c << (ser.title.empty() ? std::string(" notitle") : " title " + quoted(ser.title));
  return c.str();
}

}  // namespace

void plotSeries(const std::string& png_path, const std::vector<Series>& series,
                const SeriesPlotOptions& options) {
  checkPath(png_path);
  TempFiles temps(png_path);
  const std::string png_tmp = tmpPathFor(png_path);

  std::ostringstream s = scriptStream();
  writeHeader(s, png_tmp, options.width_px, options.height_px, options.title);
  writeSeriesAxes(s, options);
  writeRoomForBoxes(s, series, options);
  std::vector<std::string> plots;
  for (size_t i = 0; i < series.size(); ++i) {
    const std::string with = seriesStyle(series[i]);
    if (!series[i].x.empty()) plots.push_back(seriesClause(series[i], with, i, temps));
  }
  if (plots.empty()) {  // an empty frame: gnuplot refuses an empty data file
    if (!options.x_range) s << "set xrange [0:1]\n";
    if (!options.y_range) s << "set yrange [" << (options.log_y ? "1:10" : "0:1") << "]\n";
    plots.push_back("NaN notitle");
  }
  writePlotCommand(s, plots);
  render(png_path, s.str(), temps, png_tmp);
}

void plotSurface(const std::string& png_path, const std::vector<double>& x,
                 const std::vector<double>& y, const std::vector<double>& z,
                 const SurfacePlotOptions& options) {
  checkPath(png_path);
  if (x.empty() || y.empty() || z.size() != x.size() * y.size()) {
    throw std::invalid_argument("plotSurface: z must hold x.size() * y.size() values");
  }
  TempFiles temps(png_path);
  const std::string png_tmp = tmpPathFor(png_path);
  std::ostringstream s = scriptStream();
  writeHeader(s, png_tmp, options.width_px, options.height_px, options.title);
  writeAxisLabels(s, options.x_label, options.y_label);
  if (!options.z_label.empty()) s << "set zlabel " << quoted(options.z_label) << " rotate\n";
  s << "set pm3d depthorder\nset palette rgbformulae 33,13,10\n"
    << "set view 60,30\nset datafile missing 'NaN'\n";
  // One scan line per x value (gnuplot's grid format: blank line between scans).
  const std::string data_path = temps.make(".surface.tmp");
  {
    std::ofstream out(data_path, std::ios::trunc);
    out.imbue(std::locale::classic());
    out.precision(10);
    for (size_t i = 0; i < x.size(); ++i) {
      for (size_t j = 0; j < y.size(); ++j) {
        const double v = z[i * y.size() + j];
        out << x[i] << " " << y[j] << " ";
        if (std::isfinite(v)) {
          out << v << "\n";
        } else {
          out << "NaN\n";
        }
      }
      out << "\n";
    }
    out.close();
    if (!out) throw std::runtime_error("plot: cannot write temporary file " + data_path);
  }
  if (options.marker) {
    // Drawn in front of the surface (a point among the surface's would be hidden by it), with
    // a black stem up to the top of the surface so the eye finds it.
    double top = options.marker->z();
    for (double v : z) {
      if (std::isfinite(v)) top = std::max(top, v);
    }
    const Eigen::Vector3d& m = *options.marker;
    s << "set label 1 '' at " << m.x() << "," << m.y() << "," << m.z()
      << " point pt 7 ps 2.5 lc rgb 'black' front\n"
      << "set arrow 1 from " << m.x() << "," << m.y() << "," << m.z() << " to " << m.x() << ","
      << m.y() << "," << top << " nohead front lw 2 lc rgb 'black'\n";
  }
  s << "splot " << quoted(data_path) << " using 1:2:3 with pm3d notitle";
  if (options.marker) {
    const std::string marker_path = temps.make(".marker.tmp");
    std::ofstream out(marker_path, std::ios::trunc);
    out.imbue(std::locale::classic());
    out.precision(10);
    out << options.marker->x() << " " << options.marker->y() << " " << options.marker->z() << "\n";
    out.close();
    s << ", " << quoted(marker_path) << " using 1:2:3 with points pt 7 ps 2 lc rgb 'black' title "
      << quoted(options.marker_title);
  }
  s << "\n";
  render(png_path, s.str(), temps, png_tmp);
}

}  // namespace sweepmap
