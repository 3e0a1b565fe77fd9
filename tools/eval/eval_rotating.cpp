#include "tools/offline/runs.hpp"
#include "tools/eval/eval_rotating.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "calib/plate_angle.hpp"
#include "calib/rotating_geometry.hpp"
#include "calib/walls.hpp"
#include "core/calibration_file.hpp"
#include "core/event_log.hpp"
#include "mapping/plot.hpp"
#include "tools/eval/figures.hpp"
#include "tools/offline/log_sweeps.hpp"
#include "tools/offline/simulation.hpp"
#include "core/angles.hpp"

namespace sweepmap {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
constexpr double kRefitDistanceM = 0.05;  // ~4 sigma of the UST-10LX range noise

double round6(double v) { return std::round(v * 1e6) / 1e6; }

class Stopwatch {
 public:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

void progressLine(const EvalSettings& s, const std::string& line) {
  if (s.progress) std::cerr << "eval: " << line << std::endl;
}

enum class Method { kRayPlane, kCentroid, kUncorrected };
const char* methodKey(Method m) {
  switch (m) {
    case Method::kRayPlane: return "ray_plane";
    case Method::kCentroid: return "centroid";
    case Method::kUncorrected: return "uncorrected";
  }
  return "";
}

struct SweepRecord {
  std::string log;
  int64_t id = 0;
  int mode = 0;
  size_t points = 0;
  int plate_points = 0;
  // ray_plane (the default method)
  bool corrected = false;
  std::string reason;
  double phi_offset_rad = 0.0;
  double alpha_used_rad = 0.0;
  // centroid (the paper's method), from a second pass over the same log
  bool has_centroid = false;
  bool corrected_centroid = false;
  std::string reason_centroid;
  double phi_offset_centroid_rad = 0.0;
  double alpha_used_centroid_rad = 0.0;
  std::optional<double> phi_true_rad;
  // Walls of the cloud as published by the default method (Appendix B; alpha calibration)
  std::vector<Eigen::Vector3d> wall_normals;
  std::string walls_reason;
  DeviationStats deviations;

  bool correctedBy(Method m) const {
    return m == Method::kRayPlane ? corrected
                                  : m == Method::kCentroid ? corrected_centroid : true;
  }
  // phi_error of the cloud the method publishes (an uncorrected sweep keeps -phi_true).
  std::optional<double> phiErrorRad(Method m) const {
    if (!phi_true_rad) return std::nullopt;
    if (m == Method::kCentroid && !has_centroid) return std::nullopt;
    const double offset = m == Method::kRayPlane   ? (corrected ? phi_offset_rad : 0.0)
                          : m == Method::kCentroid ? (corrected_centroid ? phi_offset_centroid_rad : 0.0)
                                                   : 0.0;
    return wrapAngle(offset - *phi_true_rad);
  }
};

struct Group {
  std::vector<SweepRecord> sweeps;
  DeviationStats deviations;
  std::vector<Eigen::Vector3f> top_Op, top_O;  // Fig. 8, subsampled
  size_t first_sweep_top_points = 0;           // top_Op points of the first sweep
};

struct LogStatus {
  std::string path;
  std::string role;  // "mode", "alpha", "naive", "input"
  int sweeps = 0;
  int64_t events = 0;
  bool error = false;
  std::string message;
  std::optional<double> alpha_true_rad;
  std::string scene;
  std::map<std::string, int64_t> skipped_channels;
  double seconds = 0.0;
};

struct MethodRigs {
  RotatingLidarConfig ray_plane;
  RotatingLidarConfig centroid;
};

MethodRigs methodRigs(const RotatingLidarConfig& rig) {
  MethodRigs r{rig, rig};
  r.ray_plane.plate.beta_method = "ray_plane";
  r.centroid.plate.beta_method = "centroid";
  return r;
}

void appendTopView(const std::vector<Eigen::Vector3f>& cloud, const EvalSettings& s,
                   std::vector<Eigen::Vector3f>* out) {
  size_t in_band = 0;
  for (const auto& p : cloud) {
    if (p.z() >= s.top_view_z_min_m && p.z() <= s.top_view_z_max_m) ++in_band;
  }
  const size_t stride = std::max<size_t>(1, (in_band + s.top_view_points_per_sweep - 1) /
                                                std::max<size_t>(1, s.top_view_points_per_sweep));
  size_t k = 0;
  for (const auto& p : cloud) {
    if (p.z() < s.top_view_z_min_m || p.z() > s.top_view_z_max_m) continue;
    if (k++ % stride == 0) out->push_back(p);
  }
}

// Runs the log through the assembler twice (centroid, then ray_plane) and adds a record
// per sweep to the group `group_for(mode)` returns.
LogStatus evaluateLog(const std::string& path, const std::string& role, const MethodRigs& rigs,
                      const EvalSettings& s, bool top_views,
                      const std::function<Group&(int mode)>& group_for) {
  Stopwatch watch;
  LogStatus status;
  status.path = path;
  status.role = role;
  const std::string name = fs::path(path).filename().string();

  struct CentroidResult {
    bool corrected;
    std::string reason;
    double phi_offset_rad;
    double alpha_rad;
  };
  std::map<int64_t, CentroidResult> centroid;
  progressLine(s, name + ": pass 1/2 (beta by centroid)");
  forEachSweep(path, rigs.centroid, [&](const AssembledSweep& sw, const SweepTruth&) {
    centroid[sw.window.sweep_id] = {sw.corrected, sw.reason, sw.phi_offset_rad, sw.alpha_rad};
  });
  progressLine(s, name + ": pass 2/2 (beta by ray_plane), walls  [" + fixed(watch.seconds(), 1) +
                      " s]");

  const LogReadResult read = forEachSweep(
      path, rigs.ray_plane, [&](const AssembledSweep& sw, const SweepTruth& truth) {
        SweepRecord r;
        r.log = name;
        r.id = sw.window.sweep_id;
        r.mode = sw.window.mode;
        r.points = sw.points.size();
        r.plate_points = sw.plate.points;
        r.corrected = sw.corrected;
        r.reason = sw.reason;
        r.phi_offset_rad = sw.phi_offset_rad;
        r.alpha_used_rad = sw.alpha_rad;
        const auto c = centroid.find(r.id);
        if (c != centroid.end()) {
          r.has_centroid = true;
          r.corrected_centroid = c->second.corrected;
          r.reason_centroid = c->second.reason;
          r.phi_offset_centroid_rad = c->second.phi_offset_rad;
          r.alpha_used_centroid_rad = c->second.alpha_rad;
        }
        r.phi_true_rad = truth.phi_true_rad;

        WallExtractionOptions wo;
        wo.voxel_m = s.wall_voxel_m;
        const WallExtraction ex = extractWalls(sw.points, wo);
        r.deviations = DeviationStats(s.histogram_bin_mm, 1000.0 * s.band_m);
        if (ex.walls.empty()) {
          r.walls_reason = ex.reason.empty() ? "no walls found" : ex.reason;
        } else {
          const std::vector<WallPlaneFit> fits = refitWalls(sw.points, ex.walls, kRefitDistanceM);
          std::vector<PlaneForDeviation> planes;
          for (const auto& f : fits) {
            if (f.inliers < 3) continue;
            planes.push_back({f.normal, f.offset});
            r.wall_normals.push_back(f.normal);
          }
          for (const auto& wall : wallDeviationsMm(sw.points, planes, s.band_m, s.edge_trim_m)) {
            for (double d : wall) r.deviations.add(d, s.within_mm);
          }
        }

        Group& g = group_for(r.mode);
        if (g.deviations.bins.empty()) g.deviations = DeviationStats(s.histogram_bin_mm, 1000.0 * s.band_m);
        g.deviations.merge(r.deviations);
        if (top_views) {
          appendTopView(sw.points_Op, s, &g.top_Op);
          appendTopView(sw.points, s, &g.top_O);
          if (g.sweeps.empty()) g.first_sweep_top_points = g.top_Op.size();
        }
        std::ostringstream line;
        line << name << ": sweep " << r.id << " (mode " << r.mode << ", " << r.points
             << " points)";
        if (const auto e = r.phiErrorRad(Method::kRayPlane)) {
          line << " phi_error " << fixed(*e * kRadToDeg, 3) << " deg";
        }
        if (!r.corrected) line << " not corrected: " << r.reason;
        line << ", " << r.wall_normals.size() << " walls, RMS " << fixed(r.deviations.rmsMm(), 1)
             << " mm  [" << fixed(watch.seconds(), 1) << " s]";
        progressLine(s, line.str());
        g.sweeps.push_back(std::move(r));
        ++status.sweeps;
      });
  status.events = read.events;
  status.error = read.log_error;
  status.message = read.error;
  status.alpha_true_rad = read.alpha_true_rad;
  status.scene = read.scene;
  status.skipped_channels = read.skipped_channels;
  status.seconds = watch.seconds();
  if (status.error) progressLine(s, name + ": " + status.message);
  return status;
}

struct AlphaCalibration {
  bool done = false;
  std::string reason;  // why not done
  int sweeps_used = 0;
  double alpha0_rad = 0.0;
  double e_atti_before = 0.0;  // mean E_atti (Eq. 11) as assembled
  double e_atti_after = 0.0;   // mean f_cost at the calibrated alpha
  LmResult lm;
};

// Algorithm A1 over the wall normals of the sweeps the method corrected. The centroid
// method's clouds are the default method's rotated by (phi_c - phi_r), and so are their
// normals.
AlphaCalibration calibrateAlpha(const std::vector<const SweepRecord*>& records, Method method,
                                double alpha0_rad) {
  AlphaCalibration a;
  a.alpha0_rad = alpha0_rad;
  std::vector<SweepNormals> sweeps;
  for (const SweepRecord* r : records) {
    if (r->wall_normals.empty() || !r->corrected) continue;
    SweepNormals sn;
    if (method == Method::kCentroid) {
      if (!r->has_centroid || !r->corrected_centroid) continue;
      const Eigen::Matrix3d R = rotating::rotZ(r->phi_offset_centroid_rad - r->phi_offset_rad);
      for (const auto& n : r->wall_normals) sn.normals.push_back(R * n);
      sn.alpha_used_rad = r->alpha_used_centroid_rad;
    } else {
      sn.normals = r->wall_normals;
      sn.alpha_used_rad = r->alpha_used_rad;
    }
    sweeps.push_back(std::move(sn));
  }
  a.sweeps_used = static_cast<int>(sweeps.size());
  if (sweeps.empty()) {
    a.reason = records.empty() ? "no mode-7 sweep" : "no corrected mode-7 sweep with four walls";
    return a;
  }
  LmOptions lo;
  lo.alpha0_rad = alpha0_rad;
  a.lm = calibratePlateAngle(sweeps, lo);
  for (const auto& sn : sweeps) {
    a.e_atti_before += attitudeError(sn) / static_cast<double>(sweeps.size());
    a.e_atti_after += fCost(sn, a.lm.alpha_rad) / static_cast<double>(sweeps.size());
  }
  a.done = true;
  return a;
}

json alphaJson(const AlphaCalibration& a) {
  json j;
  j["sweeps_used"] = a.sweeps_used;
  j["alpha0_deg"] = round6(a.alpha0_rad * kRadToDeg);
  if (!a.done) {
    j["error"] = a.reason;
    return j;
  }
  j["alpha_deg"] = round6(a.lm.alpha_rad * kRadToDeg);
  j["iterations"] = a.lm.iterations;
  j["final_cost"] = a.lm.final_cost;
  j["converged"] = a.lm.converged;
  j["stop_reason"] = a.lm.stop_reason;
  j["mean_e_atti_before"] = round6(a.e_atti_before);
  j["mean_e_atti_after"] = round6(a.e_atti_after);
  json h = json::array();
  for (const auto& it : a.lm.history) {
    h.push_back({{"k", it.k}, {"alpha_deg", it.alpha_rad * kRadToDeg}, {"cost", it.cost},
                 {"mu", it.mu}});
  }
  j["history"] = h;
  return j;
}

struct PhiStats {
  int sweeps = 0;       // with an error value
  int uncorrected = 0;  // sweeps the method did not correct (left out of the stats)
  double max = 0, mean = 0, min = 0, max_abs = 0;
};

PhiStats phiStats(const std::vector<SweepRecord>& sweeps, Method m) {
  PhiStats st;
  double sum = 0;
  for (const auto& r : sweeps) {
    const auto e = r.phiErrorRad(m);
    if (!e) continue;
    if (!r.correctedBy(m)) {
      ++st.uncorrected;
      continue;
    }
    const double d = *e * kRadToDeg;
    if (st.sweeps == 0) st.max = st.min = d;
    st.max = std::max(st.max, d);
    st.min = std::min(st.min, d);
    st.max_abs = std::max(st.max_abs, std::abs(d));
    sum += d;
    ++st.sweeps;
  }
  if (st.sweeps > 0) st.mean = sum / st.sweeps;
  return st;
}

json phiStatsJson(const PhiStats& st) {
  if (st.sweeps == 0) return {{"sweeps", 0}, {"uncorrected_sweeps", st.uncorrected}};
  return {{"sweeps", st.sweeps},          {"uncorrected_sweeps", st.uncorrected},
          {"max", round6(st.max)},         {"mean", round6(st.mean)},
          {"min", round6(st.min)},         {"max_abs", round6(st.max_abs)}};
}

json deviationJson(const DeviationStats& d, const EvalSettings& s, size_t sweeps) {
  json j;
  j["points"] = d.count;
  // Bent walls (shape error) leave the band: fewer wall points per sweep.
  j["points_per_sweep"] = sweeps > 0 ? d.count / static_cast<int64_t>(sweeps) : 0;
  j["rms_mm"] = round6(d.rmsMm());
  j["share_within_40mm"] = round6(d.shareWithin());
  j["within_mm"] = s.within_mm;
  j["histogram"] = {{"bin_mm", d.bin_mm},
                    {"range_mm", d.range_mm},
                    {"counts", d.bins},
                    {"outside_range", d.outside_range}};
  return j;
}

json sweepJson(const SweepRecord& r) {
  json j;
  j["log"] = r.log;
  j["id"] = r.id;
  j["points"] = r.points;
  j["plate_points"] = r.plate_points;
  j["corrected"] = r.corrected;
  j["reason"] = r.reason;
  j["phi_offset_deg"] = round6(r.phi_offset_rad * kRadToDeg);
  if (r.has_centroid) {
    j["corrected_centroid"] = r.corrected_centroid;
    j["reason_centroid"] = r.reason_centroid;
    j["phi_offset_centroid_deg"] = round6(r.phi_offset_centroid_rad * kRadToDeg);
  }
  if (r.phi_true_rad) {
    j["phi_true_deg"] = round6(*r.phi_true_rad * kRadToDeg);
    json e;
    for (Method m : {Method::kRayPlane, Method::kCentroid, Method::kUncorrected}) {
      if (const auto v = r.phiErrorRad(m)) e[methodKey(m)] = round6(*v * kRadToDeg);
    }
    j["phi_error_deg"] = e;
  }
  j["walls"] = r.wall_normals.size();
  if (!r.walls_reason.empty()) j["walls_reason"] = r.walls_reason;
  j["wall_points"] = r.deviations.count;
  j["wall_rms_mm"] = round6(r.deviations.rmsMm());
  j["wall_share_within_40mm"] = round6(r.deviations.shareWithin());
  return j;
}

// Everything the report is made of.
struct ReportInput {
  json inputs;
  std::map<int, Group> modes;
  std::optional<Group> naive;
  std::vector<LogStatus> logs;
  AlphaCalibration alpha, alpha_centroid;
  std::string alpha_source;
  bool alpha_applied = false;  // the mode logs were evaluated with the calibrated alphas
  double alpha_eval_deg = 0.0, alpha_eval_centroid_deg = 0.0;
  std::optional<double> alpha_true_rad;
  json timings;
};

// --- figures ----------------------------------------------------------------------------

const char* methodColor(Method m) {
  switch (m) {
    case Method::kRayPlane: return "#1f4fd8";
    case Method::kCentroid: return "#1a9641";
    case Method::kUncorrected: return "#d7191c";
  }
  return "";
}

void drawFigures(const ReportInput& in, const EvalSettings& s, bool has_truth, Figures* fig) {
  // Fig. 8: top views.
  for (const auto& [mode, g] : in.modes) {
    if (g.top_O.empty()) continue;
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
               plotTopView(png,
                           {{"uncorrected C_O'", "red", g.top_Op},
                            {"corrected C_O", "blue", g.top_O}},
                           po);
             });
  }

  if (has_truth) {
    // Fig. 9: phi_error per sweep; x = mode, the sweeps of a mode spread around it.
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
    SeriesPlotOptions so;
    so.x_label = "scan mode (sweeps of a mode side by side)";
    so.y_label = "phi_error (deg)";
    so.x_range = PlotRange{0.5, 7.5};
    so.title = "Fig. 9: phi_error of every sweep, uncorrected and corrected";
    fig->add("fig9_phi_error.png",
             "Fig. 9: phi_error of every sweep (mode on the x axis): red uncorrected C_O' "
             "(= -phi_true), blue/green corrected by the plate (ray_plane / centroid).",
             [&](const std::string& png) {
               plotSeries(png,
                          {per_sweep[Method::kUncorrected], per_sweep[Method::kRayPlane],
                           per_sweep[Method::kCentroid]},
                          so);
             });
    so.title = "Fig. 9 (zoom): phi_error of every corrected sweep";
    fig->add("fig9_phi_error_corrected.png",
             "Fig. 9, zoomed on the corrected sweeps: the residual attitude error of each "
             "plate estimator.",
             [&](const std::string& png) {
               plotSeries(png, {per_sweep[Method::kRayPlane], per_sweep[Method::kCentroid]}, so);
             });

    // Fig. 10: max/mean/min per mode.
    std::vector<Series> stats_all, stats_corr;
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
        stats_all.push_back(*ser);
        if (m != Method::kUncorrected) stats_corr.push_back(*ser);
      }
    }
    so.title = "Fig. 10: max / mean / min of phi_error per mode";
    so.x_label = "scan mode";
    fig->add("fig10_phi_error_stats.png",
             "Fig. 10: maximum, mean (with points) and minimum phi_error per mode; the band "
             "between max and min is the attitude uncertainty of the mode.",
             [&](const std::string& png) { plotSeries(png, stats_all, so); });
    so.title = "Fig. 10 (zoom): max / mean / min of phi_error per mode, corrected";
    fig->add("fig10_phi_error_stats_corrected.png",
             "Fig. 10, zoomed on the corrected sweeps (blue ray_plane, green centroid).",
             [&](const std::string& png) { plotSeries(png, stats_corr, so); });

    // Fig. 11: E_map(d) per mode.
    std::vector<double> d;
    for (int i = 0; i <= 200; ++i) d.push_back(s.max_range_m * i / 200.0);
    const double lim_mm = 1000.0 * s.map_error_limit_m;
    const auto curve = [&](double phi_deg, const std::string& title, const std::string& color,
                           const std::string& style) {
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
    };
    const Series band_hi{"+-" + fixed(lim_mm, 0) + " mm", {0.0, s.max_range_m}, {lim_mm, lim_mm},
                         "lines", "black"};
    const Series band_lo{"", {0.0, s.max_range_m}, {-lim_mm, -lim_mm}, "lines", "black"};
    std::vector<Series> worst_all;
    for (const auto& [mode, g] : in.modes) {
      const PhiStats r = phiStats(g.sweeps, Method::kRayPlane);
      const PhiStats c = phiStats(g.sweeps, Method::kCentroid);
      if (r.sweeps == 0 && c.sweeps == 0) continue;
      std::vector<Series> ser = {band_hi, band_lo};
      std::string marks;
      if (r.sweeps > 0) {
        ser.push_back(curve(r.max, "ray_plane max", methodColor(Method::kRayPlane), "lines"));
        ser.push_back(curve(r.mean, "ray_plane mean", methodColor(Method::kRayPlane), "linespoints"));
        ser.push_back(curve(r.min, "ray_plane min", methodColor(Method::kRayPlane), "lines"));
        const double d50 = mapErrorDistance(r.max_abs * kDegToRad, s.map_error_limit_m, s.max_range_m);
        ser.push_back({"ray_plane: |E_map| <= " + fixed(lim_mm, 0) + " mm up to " + fixed(d50, 2) + " m",
                       {d50, d50}, {-lim_mm, lim_mm}, "linespoints", methodColor(Method::kRayPlane)});
        static const char* kModeColors[] = {"#e41a1c", "#ff7f00", "#b8a000", "#4daf4a",
                                            "#17becf", "#377eb8", "#984ea3"};
        Series w = curve(r.max_abs, "mode " + std::to_string(mode),
                         kModeColors[(mode - 1 + 7) % 7], "lines");
        worst_all.push_back(w);
      }
      if (c.sweeps > 0) {
        ser.push_back(curve(c.max, "centroid max", methodColor(Method::kCentroid), "lines"));
        ser.push_back(curve(c.min, "centroid min", methodColor(Method::kCentroid), "lines"));
        const double d50 = mapErrorDistance(c.max_abs * kDegToRad, s.map_error_limit_m, s.max_range_m);
        ser.push_back({"centroid: up to " + fixed(d50, 2) + " m", {d50, d50}, {-lim_mm, lim_mm},
                       "linespoints", methodColor(Method::kCentroid)});
      }
      SeriesPlotOptions fo;
      fo.title = "Fig. 11, mode " + std::to_string(mode) + ": E_map = d tan(phi_error)";
      fo.x_label = "distance d (m)";
      fo.y_label = "E_map (mm)";
      fo.x_range = PlotRange{0.0, s.max_range_m};
      fig->add("fig11_map_error_mode" + std::to_string(mode) + ".png",
               "Fig. 11, mode " + std::to_string(mode) +
                   ": mapping error E_map(d) for the max/mean/min phi_error of the corrected "
                   "sweeps; the vertical marks show where it leaves the +-50 mm band.",
               [&, ser](const std::string& png) { plotSeries(png, ser, fo); });
    }
    if (!worst_all.empty()) {
      worst_all.insert(worst_all.begin(), band_hi);
      SeriesPlotOptions fo;
      fo.title = "Fig. 11 (all modes): |E_map| of the worst corrected sweep (ray_plane)";
      fo.x_label = "distance d (m)";
      fo.y_label = "|E_map| (mm)";
      fo.x_range = PlotRange{0.0, s.max_range_m};
      fig->add("fig11_map_error_all.png",
               "Fig. 11, all modes: |E_map(d)| of each mode's worst corrected sweep (ray_plane); "
               "a curve under the black line stays within 50 mm.",
               [&](const std::string& png) { plotSeries(png, worst_all, fo); });
    }
  }

  // Appendix B (Fig. A2): deviation histograms.
  for (const auto& [mode, g] : in.modes) {
    if (g.deviations.count == 0) continue;
    Series h;
    h.title = "mode " + std::to_string(mode) + ": RMS " + fixed(g.deviations.rmsMm(), 1) +
              " mm, " + fixed(100.0 * g.deviations.shareWithin(), 2) + " % within +-40 mm";
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
             [&, h, lo, hi](const std::string& png) { plotSeries(png, {h, lo, hi}, fo); });
  }

  // Alpha calibration history.
  if (in.alpha.done || in.alpha_centroid.done) {
    std::vector<Series> cost, alpha;
    for (const auto* a : {&in.alpha, &in.alpha_centroid}) {
      if (!a->done) continue;
      const Method m = a == &in.alpha ? Method::kRayPlane : Method::kCentroid;
      Series c{std::string("F_cost, ") + methodKey(m), {}, {}, "linespoints", methodColor(m)};
      Series al{std::string("alpha, ") + methodKey(m), {}, {}, "linespoints", methodColor(m)};
      for (const auto& it : a->lm.history) {
        c.x.push_back(it.k);
        c.y.push_back(std::max(it.cost, 1e-30));
        al.x.push_back(it.k);
        al.y.push_back(it.alpha_rad * kRadToDeg);
      }
      cost.push_back(c);
      alpha.push_back(al);
    }
    if (in.alpha_true_rad && !alpha.empty() && !alpha.front().x.empty()) {
      double k_max = 1;
      for (const auto& ser : alpha) k_max = std::max(k_max, ser.x.back());
      alpha.push_back({"true alpha (simulator)", {0.0, k_max},
                       {*in.alpha_true_rad * kRadToDeg, *in.alpha_true_rad * kRadToDeg}, "lines",
                       "black"});
    }
    SeriesPlotOptions fo;
    fo.x_label = "LM iteration k";
    fo.title = "Alpha calibration (Algorithm A1): F_cost per iteration";
    fo.y_label = "F_cost (Eq. 20)";
    fo.log_y = true;
    fig->add("fig_alpha_calibration_cost.png",
             "Alpha calibration (Algorithm A1): the cost F_cost of Eq. 20 at each LM iteration.",
             [&](const std::string& png) { plotSeries(png, cost, fo); });
    fo.title = "Alpha calibration (Algorithm A1): alpha per iteration";
    fo.y_label = "alpha (deg)";
    fo.log_y = false;
    fig->add("fig_alpha_calibration_alpha.png",
             "Alpha calibration: the plate angle alpha at each LM iteration, from alpha_0 "
             "toward the calibrated value (black: the simulator's true alpha, when known).",
             [&](const std::string& png) { plotSeries(png, alpha, fo); });
  }

  // Fig. 1: shape error of the naive action sequence.
  if (in.naive && !in.naive->sweeps.empty()) {
    const Group& nv = *in.naive;
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
    const auto improved = in.modes.find(1);
    std::vector<Series> hs;
    const auto share = [](const DeviationStats& d, const std::string& title,
                          const std::string& color) {
      Series h{title, {}, {}, "lines", color};
      for (size_t i = 0; i < d.bins.size(); ++i) {
        h.x.push_back(d.binCenterMm(i));
        h.y.push_back(d.count > 0 ? 100.0 * static_cast<double>(d.bins[i]) / d.count : 0.0);
      }
      return h;
    };
    if (nv.deviations.count > 0) {
      hs.push_back(share(nv.deviations,
                         "naive: RMS " + fixed(nv.deviations.rmsMm(), 1) + " mm, " +
                             fixed(100 * nv.deviations.shareWithin(), 1) + " % within +-40 mm",
                         "red"));
    }
    if (improved != in.modes.end() && improved->second.deviations.count > 0) {
      const DeviationStats& d = improved->second.deviations;
      hs.push_back(share(d,
                         "improved: RMS " + fixed(d.rmsMm(), 1) + " mm, " +
                             fixed(100 * d.shareWithin(), 1) + " % within +-40 mm",
                         "blue"));
    }
    if (!hs.empty()) {
      SeriesPlotOptions fo;
      fo.title = "Fig. 1 / Appendix B, mode 1: wall deviations, naive vs improved action sequence";
      fo.x_label = "deviation (mm)";
      fo.y_label = "share of wall points (%)";
      fig->add("fig1_shape_deviations.png",
               "Shape error: wall-point deviations in mode 1, naive (red) vs improved (blue) "
               "action sequence; the naive sequence's ramps spread the walls.",
               [&](const std::string& png) { plotSeries(png, hs, fo); });
    }
  }
}

// --- report -----------------------------------------------------------------------------

void writeAtomically(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw std::runtime_error(tmp.string() + ": cannot write");
    f << text;
    f.close();
    if (!f) throw std::runtime_error(tmp.string() + ": write failed");
  }
  fs::rename(tmp, path);
}

std::string optNum(const json& j, int digits, const std::string& unit = "") {
  if (j.is_null()) return "–";
  return fixed(j.get<double>(), digits) + unit;
}

int64_t perSweep(const Group& g) {
  return g.sweeps.empty() ? 0 : g.deviations.count / static_cast<int64_t>(g.sweeps.size());
}

EvalRotatingResult writeReport(const fs::path& out, const ReportInput& in, const EvalSettings& s) {
  EvalRotatingResult result;
  bool has_truth = false;
  for (const auto& [mode, g] : in.modes) {
    result.sweeps += static_cast<int>(g.sweeps.size());
    for (const auto& r : g.sweeps) has_truth = has_truth || r.phi_true_rad.has_value();
  }
  Figures figures(out, s.plots);
  drawFigures(in, s, has_truth, &figures);

  json j;
  j["tool"] = "sweepmap eval (rotating_lidar)";
  j["inputs"] = in.inputs;
  j["sweeps"] = result.sweeps;
  j["settings"] = {{"wall_band_m", s.band_m},
                   {"wall_edge_trim_m", s.edge_trim_m},
                   {"wall_refit_distance_m", kRefitDistanceM},
                   {"wall_voxel_m", s.wall_voxel_m},
                   {"histogram_bin_mm", s.histogram_bin_mm},
                   {"map_error_limit_m", s.map_error_limit_m},
                   {"max_range_m", s.max_range_m},
                   {"d50_over", "sweeps the method corrected (uncorrected ones are counted)"}};
  json logs = json::array();
  for (const auto& l : in.logs) {
    json lj = {{"path", l.path}, {"role", l.role}, {"sweeps", l.sweeps}, {"events", l.events},
               {"seconds", round6(l.seconds)}};
    if (l.error) lj["error"] = l.message;
    if (!l.skipped_channels.empty()) lj["skipped_channels"] = l.skipped_channels;
    if (!l.scene.empty()) lj["scene"] = l.scene;
    logs.push_back(lj);
    if (l.error && !result.failed) {
      result.failed = true;
      result.message = l.path + ": " + l.message;
    }
  }
  j["logs"] = logs;

  json modes = json::object(), d50 = json::object(), d50c = json::object(), d50u = json::object();
  for (const auto& [mode, g] : in.modes) {
    json mj;
    mj["sweeps"] = json::array();
    for (const auto& r : g.sweeps) mj["sweeps"].push_back(sweepJson(r));
    const std::string key = std::to_string(mode);
    if (has_truth) {
      json pe;
      for (Method m : {Method::kRayPlane, Method::kCentroid, Method::kUncorrected}) {
        pe[methodKey(m)] = phiStatsJson(phiStats(g.sweeps, m));
      }
      mj["phi_error_deg"] = pe;
      const auto dist = [&](Method m) -> json {
        const PhiStats st = phiStats(g.sweeps, m);
        if (st.sweeps == 0) return nullptr;
        return round6(mapErrorDistance(st.max_abs * kDegToRad, s.map_error_limit_m, s.max_range_m));
      };
      d50[key] = mj["d50_m"] = dist(Method::kRayPlane);
      d50c[key] = mj["d50_m_centroid"] = dist(Method::kCentroid);
      d50u[key] = mj["d50_m_uncorrected"] = dist(Method::kUncorrected);
    }
    mj["walls"] = deviationJson(g.deviations, s, g.sweeps.size());
    modes[key] = mj;
  }
  j["modes"] = modes;
  if (has_truth) {
    j["d50_m"] = d50;
    j["d50_m_centroid"] = d50c;
    j["d50_m_uncorrected"] = d50u;
  }

  j["alpha_source"] = in.alpha_source;
  if (in.alpha.done) j["alpha_deg"] = round6(in.alpha.lm.alpha_rad * kRadToDeg);
  if (in.alpha_centroid.done) j["alpha_deg_centroid"] = round6(in.alpha_centroid.lm.alpha_rad * kRadToDeg);
  if (in.alpha_true_rad) {
    j["alpha_true_deg"] = round6(*in.alpha_true_rad * kRadToDeg);
    if (in.alpha.done) j["alpha_error_deg"] = round6((in.alpha.lm.alpha_rad - *in.alpha_true_rad) * kRadToDeg);
    if (in.alpha_centroid.done) {
      j["alpha_error_deg_centroid"] =
          round6((in.alpha_centroid.lm.alpha_rad - *in.alpha_true_rad) * kRadToDeg);
    }
  }
  j["alpha_calibration"] = {{"ray_plane", alphaJson(in.alpha)},
                            {"centroid", alphaJson(in.alpha_centroid)},
                            {"applied_to_evaluation", in.alpha_applied}};
  if (in.alpha_applied) {
    j["alpha_calibration"]["evaluated_with_alpha_deg"] = {
        {"ray_plane", round6(in.alpha_eval_deg)}, {"centroid", round6(in.alpha_eval_centroid_deg)}};
  }

  if (in.naive) {
    json sh;
    sh["naive"] = deviationJson(in.naive->deviations, s, in.naive->sweeps.size());
    sh["naive"]["sweeps"] = json::array();
    for (const auto& r : in.naive->sweeps) sh["naive"]["sweeps"].push_back(sweepJson(r));
    const auto improved = in.modes.find(1);
    if (improved != in.modes.end()) sh["improved"] = deviationJson(improved->second.deviations, s, improved->second.sweeps.size());
    sh["naive_rms_mm"] = round6(in.naive->deviations.rmsMm());
    sh["naive_share_within_40mm"] = round6(in.naive->deviations.shareWithin());
    if (improved != in.modes.end()) {
      sh["improved_rms_mm"] = round6(improved->second.deviations.rmsMm());
      sh["improved_share_within_40mm"] = round6(improved->second.deviations.shareWithin());
    }
    j["shape"] = sh;
  }
  j["figures"] = json::array();
  for (const auto& f : figures.files()) {
    j["figures"].push_back(f.file);
    result.figures.push_back(f.file);
  }
  if (!figures.errors().empty()) j["figure_errors"] = figures.errors();
  j["timings_s"] = in.timings;
  if (result.sweeps == 0 && !result.failed) {
    std::string seen;
    for (const auto& l : in.logs) {
      for (const auto& [channel, n] : l.skipped_channels) seen += (seen.empty() ? "" : ", ") + channel;
    }
    result.failed = true;
    result.message = "no sweeps in the logs: rig A's assembler needs LIDAR_SCAN and SCAN_WINDOW "
                     "(channels found: " + (seen.empty() ? std::string("none") : seen) + ")";
  }
  if (result.failed) j["error"] = result.message;
  writeAtomically(out / "report.json", j.dump(2) + "\n");

  // report.md
  std::ostringstream md;
  md << "# Rig A evaluation (Yuan 2021, section 5 and Appendix B)\n\n";
  md << "Made by `sweepmap eval (rotating_lidar)`. " << result.sweeps << " sweeps in "
     << in.modes.size() << " modes. Numbers in `report.json`.\n\n";
  if (result.failed) md << "**Error:** " << result.message << "\n\n";
  if (in.inputs.contains("experiment")) {
    const json& e = in.inputs["experiment"];
    md << "Simulated paper experiment: " << e.value("sweeps_per_mode", 0)
       << " sweeps per mode, " << e.value("calib_sweeps", 0)
       << " mode-7 sweeps for alpha, base seed " << e.value("seed", 0) << ", logs in `logs/`.\n\n";
  }
  md << "## Key numbers\n\n";
  if (in.alpha.done) {
    md << "- alpha (calibrated, " << in.alpha_source << "): "
       << fixed(in.alpha.lm.alpha_rad * kRadToDeg, 4) << " deg with beta by ray_plane";
    if (in.alpha_centroid.done) {
      md << ", " << fixed(in.alpha_centroid.lm.alpha_rad * kRadToDeg, 4) << " deg by centroid";
    }
    if (in.alpha_true_rad) {
      md << "; true " << fixed(*in.alpha_true_rad * kRadToDeg, 4) << " deg (error "
         << fixed((in.alpha.lm.alpha_rad - *in.alpha_true_rad) * kRadToDeg, 4) << " deg)";
    }
    md << "; LM: " << in.alpha.lm.iterations << " iterations, " << in.alpha.lm.stop_reason
       << ", " << in.alpha.sweeps_used << " sweeps.\n";
    md << (in.alpha_applied ? "- The mode logs were evaluated with the calibrated alpha of each "
                              "method.\n"
                            : "- The logs were evaluated with the rig's alpha (plate.alpha_deg = " +
                                  fixed(in.alpha_eval_deg, 4) + " deg), not the calibrated one.\n");
  } else {
    md << "- alpha not calibrated: " << in.alpha.reason << "\n";
  }
  if (in.naive) {
    const auto improved = in.modes.find(1);
    md << "- Shape (mode 1 walls): naive sequence RMS " << fixed(in.naive->deviations.rmsMm(), 1)
       << " mm, " << fixed(100 * in.naive->deviations.shareWithin(), 2) << " % within +-40 mm, "
       << perSweep(*in.naive) << " wall points per sweep";
    if (improved != in.modes.end()) {
      md << "; improved RMS " << fixed(improved->second.deviations.rmsMm(), 1) << " mm, "
         << fixed(100 * improved->second.deviations.shareWithin(), 2) << " %, "
         << perSweep(improved->second) << " wall points per sweep (bent walls leave the "
         << fixed(1000 * s.band_m, 0) << " mm band)";
    }
    md << ".\n";
  }
  md << "\n| mode | sweeps | phi_error uncorrected min / mean / max (deg) | max abs(phi_error) "
        "ray_plane / centroid (deg) | d50 ray_plane (m) | d50 centroid (m) | d50 uncorrected (m) "
        "| wall RMS (mm) | within +-40 mm |\n";
  md << "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const auto& [mode, g] : in.modes) {
    const json& mj = modes[std::to_string(mode)];
    md << "| " << mode << " | " << g.sweeps.size() << " | ";
    if (has_truth) {
      const PhiStats u = phiStats(g.sweeps, Method::kUncorrected);
      const PhiStats r = phiStats(g.sweeps, Method::kRayPlane);
      const PhiStats c = phiStats(g.sweeps, Method::kCentroid);
      md << fixed(u.min, 3) << " / " << fixed(u.mean, 3) << " / " << fixed(u.max, 3) << " | "
         << (r.sweeps ? fixed(r.max_abs, 4) : "–") << " / " << (c.sweeps ? fixed(c.max_abs, 4) : "–")
         << " | " << optNum(mj["d50_m"], 3) << " | " << optNum(mj["d50_m_centroid"], 3) << " | "
         << optNum(mj["d50_m_uncorrected"], 3) << " | ";
    } else {
      md << "no truth | – | – | – | – | ";
    }
    md << fixed(g.deviations.rmsMm(), 1) << " | " << fixed(100 * g.deviations.shareWithin(), 2)
       << " % |\n";
  }
  md << "\nd50: the distance at which the worst corrected sweep's mapping error "
        "|E_map| = d tan|phi_error| (Eq. 21) reaches "
     << fixed(1000 * s.map_error_limit_m, 0) << " mm, capped at " << fixed(s.max_range_m, 0)
     << " m (paper: 2.2996 m in mode 1, 10 m in mode 7). Wall deviations: points within "
     << fixed(1000 * s.band_m, 0) << " mm of the four walls' planes (refit within "
     << fixed(1000 * kRefitDistanceM, 0) << " mm), " << fixed(1000 * s.edge_trim_m, 0)
     << " mm off their edges and corners.\n\n";
  md << "## Figures\n\n";
  for (const auto& f : figures.files()) {
    md << "![" << f.file << "](" << f.file << ")\n\n" << f.caption << "\n\n";
  }
  if (!figures.errors().empty()) {
    md << "Figures not drawn:\n\n";
    for (const auto& e : figures.errors()) md << "- " << e << "\n";
  }
  writeAtomically(out / "report.md", md.str());
  return result;
}

std::optional<double> firstAlphaTruth(const std::vector<LogStatus>& logs) {
  for (const auto& l : logs) {
    if (l.alpha_true_rad) return l.alpha_true_rad;
  }
  return std::nullopt;
}

std::vector<const SweepRecord*> mode7Records(const std::map<int, Group>& groups) {
  std::vector<const SweepRecord*> out;
  const auto it = groups.find(7);
  if (it == groups.end()) return out;
  for (const auto& r : it->second.sweeps) out.push_back(&r);
  return out;
}

// The simulated error model (every sim.* key) and the keys that shape the experiment.
json simSettingsJson(const RotatingLidarConfig& rig) {
  const SimRigConfig& sim = rig.sim;
  return {{"sim.alpha_true_deg", sim.alpha_true_deg},
          {"sim.lidar_offset_x_mm", sim.lidar_offset_x_mm},
          {"sim.range_noise_sigma_mm", sim.range_noise_sigma_mm},
          {"sim.accel_jitter", sim.accel_jitter},
          {"sim.start_delay_max_ms", sim.start_delay_max_ms},
          {"sim.switch_response_ms", sim.switch_response_ms},
          {"sim.switch_response_jitter_ms", sim.switch_response_jitter_ms},
          {"sim.switch_hysteresis_deg", sim.switch_hysteresis_deg},
          {"sim.lidar_latency_ms", sim.lidar_latency_ms},
          {"motor.accel_deg_s2", rig.motor.accel_deg_s2},
          {"motor.margin_s", rig.motor.margin_s},
          {"motor.rehome_every_sweep", rig.motor.rehome_every_sweep},
          {"plate.alpha_deg", rig.plate.alpha_deg},
          {"geometry.lidar_offset_x_mm", rig.geometry.lidar_offset_x_mm}};
}

}  // namespace

// --- entry points ------------------------------------------------------------------------

EvalRotatingResult evalRotatingLogs(const EvalRotatingOptions& o) {
  Stopwatch total;
  if (o.logs.empty()) throw std::runtime_error("no logs given");
  for (const auto& l : o.logs) {
    if (!fs::exists(l)) throw std::runtime_error(l + ": no such log");
  }
  const fs::path out(o.out_dir);
  fs::create_directories(out);
  const EvalSettings& s = o.settings;
  const MethodRigs rigs = methodRigs(o.rig);

  ReportInput in;
  in.inputs = {{"logs", o.logs}, {"rig", o.rig_path}, {"overrides", o.overrides}};
  for (size_t i = 0; i < o.logs.size(); ++i) {
    progressLine(s, "log " + std::to_string(i + 1) + "/" + std::to_string(o.logs.size()) + ": " +
                        o.logs[i]);
    in.logs.push_back(evaluateLog(o.logs[i], "input", rigs, s, s.plots,
                                  [&](int mode) -> Group& { return in.modes[mode]; }));
  }
  in.alpha_true_rad = firstAlphaTruth(in.logs);
  in.alpha_source = "the mode-7 sweeps of the logs";
  const double alpha0 = o.rig.plate.alpha_deg * kDegToRad;
  Stopwatch lm_watch;
  in.alpha = calibrateAlpha(mode7Records(in.modes), Method::kRayPlane, alpha0);
  in.alpha_centroid = calibrateAlpha(mode7Records(in.modes), Method::kCentroid, alpha0);
  in.alpha_eval_deg = in.alpha_eval_centroid_deg = o.rig.plate.alpha_deg;
  in.timings["evaluate_logs"] = round6(total.seconds() - lm_watch.seconds());
  in.timings["alpha_calibration"] = round6(lm_watch.seconds());
  Stopwatch report_watch;
  in.timings["total"] = round6(total.seconds());
  EvalRotatingResult r = writeReport(out, in, s);
  progressLine(s, "report and figures: " + fixed(report_watch.seconds(), 1) + " s; total " +
                      fixed(total.seconds(), 1) + " s -> " + (out / "report.md").string());
  return r;
}

EvalRotatingResult runPaperExperiment(const PaperExperimentOptions& o) {
  Stopwatch total;
  if (o.sweeps_per_mode < 1) throw std::runtime_error("--sweeps-per-mode must be at least 1");
  if (o.calib_sweeps < 1) throw std::runtime_error("--calib-sweeps must be at least 1");
  const SimSetup setup = loadSimSetup(o.rig_path, o.scene_path, o.overrides);
  const RotatingLidarConfig rig = requireKind<RotatingLidarConfig>(setup.rig, "this experiment");
  const SceneConfig scene = setup.scene;
  const fs::path out(o.out_dir);
  fs::create_directories(out / "logs");
  const EvalSettings& s = o.settings;
  ReportInput in;
  json timings;

  json seeds = json::object();
  const auto simulateLog = [&](const std::string& file, int mode, const std::string& sequence,
                               int sweeps, uint64_t seed) {
    Stopwatch w;
    SimOptions so;
    so.rig = rig;
    so.rig.motor.mode = mode;
    so.rig.motor.action_sequence = sequence;
    so.scene = scene;
    so.sweeps = sweeps;
    so.seed = seed;
    const std::string path = (out / "logs" / file).string();
    progressLine(s, "simulating " + file + ": mode " + std::to_string(mode) + ", " + sequence +
                        " sequence, " + std::to_string(sweeps) + " sweeps, seed " +
                        std::to_string(seed));
    EventLogWriter log(path);
    const SimResult r = simulate(so, [&](const Message& m) { log.write(m.utime, m.channel, m.data); });
    log.close();
    progressLine(s, "  " + std::to_string(r.sweeps_done) + " sweeps, " +
                        fixed(r.simulated_us / 1e6, 1) + " s simulated in " + fixed(w.seconds(), 1) +
                        " s");
    if (r.motor_fault || r.sweeps_done != sweeps) {
      std::cerr << "eval: " << file << ": only " << r.sweeps_done << " of " << sweeps
                << " sweeps simulated" << (r.motor_fault ? " (motor fault)" : "") << "\n";
    }
    seeds[file] = seed;
    timings["simulate_" + file] = round6(w.seconds());
    return path;
  };

  // 1. Alpha from the mode-7 calibration log, assembled with the rig's (nominal) alpha.
  const std::string calib_log = simulateLog("alpha_mode7.lcmlog", 7, "improved", o.calib_sweeps,
                                            o.seed + 100);
  std::map<int, Group> calib_groups;
  {
    Stopwatch w;
    in.logs.push_back(evaluateLog(calib_log, "alpha", methodRigs(rig), s, false,
                                  [&](int mode) -> Group& { return calib_groups[mode]; }));
    timings["evaluate_alpha_log"] = round6(w.seconds());
  }
  std::vector<const SweepRecord*> calib_records;
  for (const auto& [mode, g] : calib_groups) {
    for (const auto& r : g.sweeps) calib_records.push_back(&r);
  }
  {
    Stopwatch w;
    const double alpha0 = rig.plate.alpha_deg * kDegToRad;
    in.alpha = calibrateAlpha(calib_records, Method::kRayPlane, alpha0);
    in.alpha_centroid = calibrateAlpha(calib_records, Method::kCentroid, alpha0);
    timings["alpha_calibration"] = round6(w.seconds());
  }
  in.alpha_source = std::to_string(o.calib_sweeps) + " simulated mode-7 sweeps";
  if (!in.alpha.done) {
    throw std::runtime_error("alpha calibration failed: " + in.alpha.reason);
  }
  const double alpha_deg = in.alpha.lm.alpha_rad * kRadToDeg;
  const double alpha_c_deg =
      in.alpha_centroid.done ? in.alpha_centroid.lm.alpha_rad * kRadToDeg : rig.plate.alpha_deg;
  progressLine(s, "alpha calibrated: " + fixed(alpha_deg, 4) + " deg (ray_plane), " +
                      fixed(alpha_c_deg, 4) + " deg (centroid), from " +
                      std::to_string(in.alpha.sweeps_used) + " sweeps");
  {
    PlateCalibration pc;
    pc.alpha_deg = alpha_deg;
    pc.source = {{"tool", "sweepmap eval (rotating_lidar) --experiment paper"},
                 {"method", "LM over wall normals (Yuan 2021 Algorithm A1), beta by ray_plane"},
                 {"sweeps", std::to_string(in.alpha.sweeps_used)}};
    pc.logs = {fs::path(calib_log).filename().string()};
    writePlateCalibration((out / "plate_calibration.yaml").string(), pc);
  }

  // 2. The 7 modes x N sweeps, evaluated with the calibrated alpha of each method.
  RotatingLidarConfig eval_rig = rig;
  eval_rig.plate.calibration_file.clear();
  MethodRigs rigs = methodRigs(eval_rig);
  rigs.ray_plane.plate.alpha_deg = alpha_deg;
  rigs.centroid.plate.alpha_deg = alpha_c_deg;
  in.alpha_applied = true;
  in.alpha_eval_deg = alpha_deg;
  in.alpha_eval_centroid_deg = alpha_c_deg;
  for (int mode = 1; mode <= 7; ++mode) {
    const std::string file = "mode" + std::to_string(mode) + ".lcmlog";
    const std::string path = simulateLog(file, mode, "improved", o.sweeps_per_mode, o.seed + mode);
    Stopwatch w;
    in.logs.push_back(evaluateLog(path, "mode", rigs, s, s.plots,
                                  [&](int m) -> Group& { return in.modes[m]; }));
    timings["evaluate_" + file] = round6(w.seconds());
  }

  // 3. Mode 1 with the naive action sequence (shape error, Fig. 1).
  if (o.naive) {
    const std::string path =
        simulateLog("mode1_naive.lcmlog", 1, "naive", o.sweeps_per_mode, o.seed + 200);
    Stopwatch w;
    in.naive.emplace();
    in.logs.push_back(evaluateLog(path, "naive", rigs, s, s.plots,
                                  [&](int) -> Group& { return *in.naive; }));
    timings["evaluate_mode1_naive.lcmlog"] = round6(w.seconds());
  }

  in.alpha_true_rad = firstAlphaTruth(in.logs);
  in.inputs = {{"rig", o.rig_path},
               {"scene", o.scene_path},
               {"overrides", o.overrides},
               {"experiment",
                {{"name", "paper"},
                 {"seed", o.seed},
                 {"sweeps_per_mode", o.sweeps_per_mode},
                 {"calib_sweeps", o.calib_sweeps},
                 {"naive", o.naive},
                 {"seeds", seeds},
                 {"plate_calibration", "plate_calibration.yaml"},
                 {"simulator", simSettingsJson(rig)}}}};
  timings["total_before_report"] = round6(total.seconds());
  Stopwatch report_watch;
  in.timings = timings;
  EvalRotatingResult r = writeReport(out, in, s);
  progressLine(s, "report and figures: " + fixed(report_watch.seconds(), 1) + " s; total " +
                      fixed(total.seconds(), 1) + " s -> " + (out / "report.md").string());
  return r;
}

}  // namespace sweepmap
