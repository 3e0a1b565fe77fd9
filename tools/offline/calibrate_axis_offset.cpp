// `sweepmap calib axis-offset`'s workflow in named steps: check the inputs, read the logs'
// plate sweeps, the paper's grid search and its figure, ours, write the file, report.
#include "tools/offline/calibrate_axis_offset.hpp"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "core/angles.hpp"
#include "core/calibration_file.hpp"
#include "core/exit_codes.hpp"
#include "mapping/plot.hpp"
#include "tools/offline/calibrate_common.hpp"
#include "tools/offline/calibrate_logs.hpp"
#include "tools/offline/profile_log.hpp"

namespace sweepmap {
namespace {

using calib_workflow::kCalibAxisOffset;

using calib_workflow::Clock;
using calib_workflow::seconds;

using Inputs = PlateSweeps;

bool checkInputs(const AxisOffsetCalibRequest& o, RotatingProfileConfig* rig) {
  if (!calib_workflow::loadRigOfKind(o.rig, o.sets, kCalibAxisOffset, rig)) return false;
  for (const auto& log : o.logs) {
    if (!calib_workflow::logFileExists(log, kCalibAxisOffset)) return false;
  }
  return calib_workflow::outputDirExists(o.out, kCalibAxisOffset);
}

std::string figurePath(const AxisOffsetCalibRequest& o) {
  if (!o.figure.empty()) return o.figure;
  std::filesystem::path p(o.out);
  return (p.parent_path() / (p.stem().string() + "_S.png")).string();
}

void writeCalibration(const AxisOffsetCalibRequest& o, const Inputs& in, const AxisOffsetResult& r,
                      const std::optional<GridSearchResult>& grid) {
  AxisOffsetCalibration c;
  c.m_mm = r.geometry.m_mm;
  c.n_mm = r.geometry.n_mm;
  c.laser_tilt_deg = r.geometry.laser_tilt_rad * kRadToDeg;
  c.encoder_zero_deg = r.geometry.encoder_zero_rad * kRadToDeg;
  const auto num = [](double v) {
    std::ostringstream s;
    s << std::setprecision(6) << v;
    return s.str();
  };
  c.source["tool"] = "sweepmap calib axis-offset";
  c.source["method"] = "ceres: M, N, planes" + std::string(r.tilt_estimated ? ", laser tilt" : "") +
                       (r.zero_estimated ? ", encoder zero" : "");
  c.source["planes"] = std::to_string(in.planes.size());
  c.source["sigma_m_mm"] = num(r.sigma_m_mm);
  c.source["sigma_n_mm"] = num(r.sigma_n_mm);
  if (r.tilt_estimated) c.source["sigma_laser_tilt_deg"] = num(r.sigma_tilt_deg);
  if (r.zero_estimated) c.source["sigma_encoder_zero_deg"] = num(r.sigma_zero_deg);
  c.source["rms_after_mm"] = num(r.rms_after_mm);
  if (grid) {
    c.source["paper_grid_m_mm"] = num(grid->m_mm);
    c.source["paper_grid_n_mm"] = num(grid->n_mm);
  }
  c.logs = o.logs;
  writeAxisOffsetCalibration(o.out, c);
}

void reportHuman(const AxisOffsetCalibRequest& o, const Inputs& in, const AxisOffsetResult& r,
                 const std::optional<GridSearchResult>& grid, const std::string& figure,
                 const std::string& figure_error, bool written) {
  std::cerr << std::fixed << std::setprecision(4);
  if (grid) {
    std::cerr << kCalibAxisOffset << ": paper (Algorithm 1, " << grid->m_values.size() << " x "
              << grid->n_values.size() << " nodes of " << o.grid.step_mm
              << " mm): M = " << grid->m_mm << " mm, N = " << grid->n_mm
              << " mm, min S = " << grid->s_min_mm << " mm, " << std::setprecision(3)
              << grid->seconds << " s\n";
    std::cerr << "  figure: " << (figure_error.empty() ? figure : "not drawn: " + figure_error)
              << "\n";
  }
  std::cerr << std::setprecision(4) << kCalibAxisOffset << ": ours (Ceres, " << r.residuals
            << " residuals): M = " << r.geometry.m_mm << " +- " << r.sigma_m_mm
            << " mm, N = " << r.geometry.n_mm << " +- " << r.sigma_n_mm << " mm";
  if (r.tilt_estimated) {
    std::cerr << ", laser tilt = " << r.geometry.laser_tilt_rad * kRadToDeg << " +- "
              << r.sigma_tilt_deg << " deg";
  }
  if (r.zero_estimated) {
    std::cerr << ", encoder zero = " << r.geometry.encoder_zero_rad * kRadToDeg << " +- "
              << r.sigma_zero_deg << " deg";
  }
  std::cerr << "\n  RMS point-to-plane " << r.rms_before_mm << " mm (nominal) -> " << r.rms_after_mm
            << " mm, " << r.iterations << " iterations" << (r.converged ? "" : " (NOT converged)")
            << ", " << std::setprecision(3) << r.seconds << " s\n";
  for (const auto& w : r.warnings) std::cerr << "  warning: " << w << "\n";
  if (in.truth) {
    std::cerr << std::setprecision(4) << "  truth M = " << in.truth->geometry.m_mm
              << ", N = " << in.truth->geometry.n_mm << ": ours off by "
              << r.geometry.m_mm - in.truth->geometry.m_mm << ", "
              << r.geometry.n_mm - in.truth->geometry.n_mm << " mm";
    if (grid) {
      std::cerr << "; paper's grid off by " << grid->m_mm - in.truth->geometry.m_mm << ", "
                << grid->n_mm - in.truth->geometry.n_mm << " mm";
    }
    std::cerr << "\n";
  }
  std::cerr << "  " << (written ? "wrote " + o.out : std::string("nothing written")) << "\n";
  std::cerr.unsetf(std::ios::floatfield);
}

nlohmann::json resultJson(const AxisOffsetCalibRequest& o, const Inputs& in,
                          const AxisOffsetResult& r, const std::optional<GridSearchResult>& grid,
                          const std::string& figure, const std::string& figure_error) {
  const auto orNull = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; };
  nlohmann::json j;
  j["ours"] = {{"m_mm", r.geometry.m_mm},
               {"n_mm", r.geometry.n_mm},
               {"laser_tilt_deg", r.geometry.laser_tilt_rad * kRadToDeg},
               {"encoder_zero_deg", r.geometry.encoder_zero_rad * kRadToDeg},
               {"sigma_m_mm", orNull(r.sigma_m_mm)},
               {"sigma_n_mm", orNull(r.sigma_n_mm)},
               {"sigma_laser_tilt_deg", orNull(r.sigma_tilt_deg)},
               {"sigma_encoder_zero_deg", orNull(r.sigma_zero_deg)},
               {"laser_tilt_estimated", r.tilt_estimated},
               {"encoder_zero_estimated", r.zero_estimated},
               {"observable", r.observable},
               {"smallest_singular_value", r.smallest_singular_value},
               {"largest_plane_angle_deg", r.largest_plane_angle_deg},
               {"rms_before_mm", r.rms_before_mm},
               {"rms_after_mm", r.rms_after_mm},
               {"iterations", r.iterations},
               {"converged", r.converged},
               {"residuals", r.residuals},
               {"seconds", r.seconds}};
  if (grid) {
    j["paper"] = {{"m_mm", grid->m_mm},
                  {"n_mm", grid->n_mm},
                  {"s_min_mm", grid->s_min_mm},
                  {"step_mm", o.grid.step_mm},
                  {"m_interval_mm", {o.grid.m_min_mm, o.grid.m_max_mm}},
                  {"n_interval_mm", {o.grid.n_min_mm, o.grid.n_max_mm}},
                  {"evaluations", grid->s_mm.size()},
                  {"seconds", grid->seconds},
                  {"figure", figure_error.empty() ? nlohmann::json(figure) : nullptr}};
  }
  j["warnings"] = r.warnings;
  j["rejected"] = in.rejected;
  nlohmann::json planes = nlohmann::json::array();
  for (size_t k = 0; k < in.planes.size(); ++k) {
    const FittedPlane& f = r.planes[k];
    planes.push_back({{"source", in.planes[k].source},
                      {"points", in.full_points[k]},
                      {"points_used", in.planes[k].samples.size()},
                      {"normal", {f.normal.x(), f.normal.y(), f.normal.z()}},
                      {"distance_mm", f.distance_mm},
                      {"rms_mm", f.rms_mm}});
  }
  j["planes"] = planes;
  if (in.truth) {
    const ProfileGeometry& t = in.truth->geometry;
    j["truth"] = {{"m_mm", t.m_mm},
                  {"n_mm", t.n_mm},
                  {"laser_tilt_deg", t.laser_tilt_rad * kRadToDeg},
                  {"encoder_zero_deg", t.encoder_zero_rad * kRadToDeg}};
    j["offset_error_mm"]["ours"] = {{"M", r.geometry.m_mm - t.m_mm},
                                    {"N", r.geometry.n_mm - t.n_mm}};
    if (grid)
      j["offset_error_mm"]["paper"] = {{"M", grid->m_mm - t.m_mm}, {"N", grid->n_mm - t.n_mm}};
  }
  j["out"] = o.out;
  return j;
}

}  // namespace

std::vector<size_t> useReferenceFace(const TurntableReference& ref,
                                     const std::vector<PlanePoints>& planes,
                                     AxisOffsetOptions* options) {
  if (!ref.declared) return {};
  options->reference_azimuth_rad = ref.normal_azimuth_deg * kDegToRad;
  options->reference_azimuth_sigma_rad = ref.azimuth_sigma_deg * kDegToRad;
  const std::vector<size_t> found =
      findReferencePlanes(planes, options->initial, options->reference_azimuth_rad,
                          ref.normal_tilt_deg * kDegToRad, kReferenceToleranceDeg * kDegToRad);
  // Two sweeps that look like the face: a plate pose laid like it cannot be told from it, and
  // holding a hand-placed pose to the face's azimuth would move the zero by that pose's error
  // while its sigma stayed the fence's. Neither is used.
  if (found.size() == 1) options->reference_planes = found;
  return found;
}

std::string drawAxisOffsetSurface(const std::string& png, const GridSearchResult& g) {
  if (!gnuplotAvailable()) return "gnuplot is not installed";
  SurfacePlotOptions p;
  p.title = "Zhao 2021 Algorithm 1: mean plane RMSE S(M, N)";
  p.x_label = "M [mm]";
  p.y_label = "N [mm]";
  p.z_label = "S [mm]";
  p.marker = Eigen::Vector3d(g.m_mm, g.n_mm, g.s_min_mm);
  std::ostringstream t;
  t << "min S at M = " << g.m_mm << ", N = " << g.n_mm << " mm";
  p.marker_title = t.str();
  try {
    plotSurface(png, g.m_values, g.n_values, g.s_mm, p);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

namespace {

// Without --encoder-zero: when the logs hold the base's reference face (one sweep, as calib
// rig recognises it), the zero calib rig would find there; a warning into r when it is more
// than 3 sigma from the rig file's (the cloud is turned by the difference about the axis).
void checkEncoderZero(const RotatingProfileConfig& rig, const Inputs& in,
                      const AxisOffsetOptions& used, AxisOffsetResult* r) {
  AxisOffsetOptions options = used;
  options.estimate_encoder_zero = true;
  const std::vector<size_t> face = useReferenceFace(rig.turntable.reference, in.planes, &options);
  if (face.size() != 1) return;
  const AxisOffsetResult z = solveAxisOffset(in.planes, options);
  if (!z.zero_estimated || !(z.sigma_zero_deg > 0)) return;
  const double zero_deg = z.geometry.encoder_zero_rad * 180.0 / M_PI;
  if (!(std::abs(zero_deg - rig.geometry.encoder_zero_deg) > 3.0 * z.sigma_zero_deg)) return;
  std::ostringstream w;
  w << std::fixed << std::setprecision(3) << "the base's reference face ("
    << in.planes[face[0]].source << ") puts the encoder zero at " << zero_deg << " +- "
    << z.sigma_zero_deg << " deg, the rig file's " << rig.geometry.encoder_zero_deg
    << " deg: the cloud is turned by the difference about the axis; run `sweepmap calib rig` "
       "(or this command with --encoder-zero)";
  r->warnings.push_back(w.str());
}

}  // namespace

int calibrateAxisOffsetFromLogs(const AxisOffsetCalibRequest& o) {
  RotatingProfileConfig rig;
  if (!checkInputs(o, &rig)) return kExitUsage;
  Inputs in;
  if (!readPlateSweeps(o.logs, {o.min_points_per_sweep, o.max_points_per_sweep}, kCalibAxisOffset,
                       /*say_each=*/true, &in))
    return kExitBadInput;
  if (in.planes.empty()) {
    std::cerr << kCalibAxisOffset << ": no sweep with " << o.min_points_per_sweep
              << " or more points in the logs: nothing calibrated\n";
    return 1;
  }
  std::optional<GridSearchResult> grid;
  std::string figure, figure_error;
  if (!o.no_grid) {
    try {
      grid = gridSearchAxisOffset(in.planes, o.grid);
    } catch (const std::invalid_argument& e) {
      std::cerr << kCalibAxisOffset << ": " << e.what() << "\n";
      return kExitUsage;
    }
    figure = figurePath(o);
    figure_error = drawAxisOffsetSurface(figure, *grid);
  }
  AxisOffsetOptions options;
  options.initial = rig.geometry.toGeometry();
  options.estimate_tilt = o.estimate_tilt;
  options.estimate_encoder_zero = o.estimate_encoder_zero;
  if (o.estimate_encoder_zero) useReferenceFace(rig.turntable.reference, in.planes, &options);
  AxisOffsetResult r = solveAxisOffset(in.planes, options);
  if (!o.estimate_encoder_zero && r.observable) checkEncoderZero(rig, in, options, &r);
  bool written = false;
  if (r.observable) {
    try {
      writeCalibration(o, in, r, grid);
      written = true;
    } catch (const std::exception& e) {
      std::cerr << kCalibAxisOffset << ": " << e.what() << "\n";
      return kExitDeviceIo;
    }
  }
  reportHuman(o, in, r, grid, figure, figure_error, written);
  if (o.json) {
    std::cout << std::setprecision(12) << resultJson(o, in, r, grid, figure, figure_error).dump(2)
              << "\n";
  }
  return written ? 0 : 1;
}

}  // namespace sweepmap
