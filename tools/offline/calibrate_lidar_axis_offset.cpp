// `sweepmap calib axis-offset --rig <rotating_lidar>`'s workflow in named steps: check the
// inputs, read the logs' sweeps and segment their planes, solve, write the file, report.
#include "tools/offline/calibrate_lidar_axis_offset.hpp"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "calib/rig_calibration.hpp"
#include "calib/rotating_geometry.hpp"
#include "core/angles.hpp"
#include "core/calibration_file.hpp"
#include "core/event_log.hpp"
#include "core/exit_codes.hpp"
#include "tools/offline/calibrate_common.hpp"
#include "tools/offline/calibrate_logs.hpp"
#include "tools/offline/calibrate_rig.hpp"
#include "tools/offline/log_sweeps.hpp"

namespace sweepmap {
namespace {

using calib_workflow::kCalibAxisOffset;

using calib_workflow::Clock;
using calib_workflow::seconds;

struct LidarInputs {
  std::vector<LidarPlaneRays> planes;
  // Per sweep used, the joint check's plate rays (its planes are in `planes`, plane_counts
  // of them each, in order).
  std::vector<RigASweep> sweeps;
  std::vector<size_t> plane_counts;
  int sweeps_used = 0;
  std::vector<std::string> rejected;    // "LOG sweep ID: why"
  std::vector<std::string> log_errors;  // corrupt tails (the sweeps before them are used)
  std::optional<double> truth_x_mm;     // TRUTH_RIG (simulated logs)
  double read_s = 0.0, segment_s = 0.0, joint_s = 0.0;
};

bool checkInputs(const LidarAxisOffsetCalibRequest& o, RotatingLidarConfig* rig) {
  if (!calib_workflow::loadRigOfKind(o.rig, o.sets, kCalibAxisOffset, rig)) return false;
  for (const auto& log : o.logs) {
    if (!calib_workflow::logFileExists(log, kCalibAxisOffset)) return false;
  }
  return calib_workflow::outputDirExists(o.out, kCalibAxisOffset);
}

// One sweep: its rays placed again (the scans it came from) and its planes into in->planes,
// or why not into in->rejected; a line on stderr either way.
void takeSweep(const LidarAxisOffsetCalibRequest& o, const RotatingLidarConfig& rig,
               const std::string& log, const AssembledSweep& s, const std::vector<Scan2D>& scans,
               LidarInputs* in) {
  const std::string source = log + " sweep " + std::to_string(s.window.sweep_id);
  const auto reject = [&](const std::string& why) {
    in->rejected.push_back(source + ": " + why);
    std::cerr << "  " << source << ": rejected: " << why << "\n";
  };
  // Frame O' is enough (each sweep has its own planes): a sweep without plate serves; a
  // window with a motor ramp does not (its shaft speed was not constant).
  if (s.window.accel_overlap) return reject("motor ramp overlapped the lidar window");
  std::vector<SweepRay> rays;
  rays.reserve(s.points_Op.size());
  forEachSweepRay(scans, s.window.omega_rad_s, [&](const SweepRay& r) { rays.push_back(r); });
  const auto t0 = Clock::now();
  std::vector<LidarPlaneRays> planes =
      segmentSweepPlanes(s.points_Op, rays, o.segmentation, source);
  in->segment_s += seconds(Clock::now() - t0);
  if (planes.empty())
    return reject("no plane of " + std::to_string(o.segmentation.min_inliers) + " points or more");
  size_t used = 0;
  for (const auto& p : planes) used += p.rays.size();
  std::cerr << "  " << source << ": " << s.points_Op.size() << " points, " << planes.size()
            << " planes, " << used << " rays used\n";
  ++in->sweeps_used;
  RigASweep sweep;
  sweep.source = source;
  takePlateCandidates(rays, rigAValuesOf(rig), PlateRegion::fromConfig(rig.plate), &sweep);
  in->sweeps.push_back(std::move(sweep));
  in->plane_counts.push_back(planes.size());
  for (auto& p : planes) in->planes.push_back(std::move(p));
}

// Every sweep of every log through takeSweep; false (after saying so) if a log cannot be
// opened. A corrupt tail is noted and what came before used.
bool readLogs(const LidarAxisOffsetCalibRequest& o, const RotatingLidarConfig& rig,
              LidarInputs* in) {
  const auto t0 = Clock::now();
  LidarLogReading r;
  r.take_sweep = [&](const std::string& log, const AssembledSweep& s,
                     const std::vector<Scan2D>& scans) { takeSweep(o, rig, log, s, scans, in); };
  r.took_log = [&](const LogReadResult& l) {
    if (l.lidar_offset_x_true_m && !in->truth_x_mm) in->truth_x_mm = *l.lidar_offset_x_true_m * 1e3;
  };
  if (!readLidarLogs(o.logs, rig, kCalibAxisOffset, r, &in->log_errors)) return false;
  in->read_s = seconds(Clock::now() - t0) - in->segment_s;
  return true;
}

std::string num(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

void writeCalibration(const LidarAxisOffsetCalibRequest& o, const RotatingLidarConfig& rig,
                      const LidarInputs& in, const LidarAxisOffsetResult& r) {
  LidarOffsetCalibration c;
  c.lidar_offset_x_mm = r.offset_mm.x();
  c.source["tool"] = "sweepmap calib axis-offset";
  c.source["method"] = "ceres: t_L^O' x" + std::string(r.y_estimated ? ", y" : "") +
                       " and every plane (PCL RANSAC planes of each sweep), Cauchy weights";
  c.source["nominal_mm"] = num(rig.geometry.lidar_offset_x_mm);
  c.source["sigma_mm"] = num(r.sigma_x_mm);
  c.source["sweeps"] = std::to_string(in.sweeps_used);
  size_t planes = 0;
  for (const size_t n : in.plane_counts) planes += n;
  c.source["planes"] = std::to_string(planes);
  c.source["wall_rms_before_mm"] = num(r.wall_rms_before_mm);
  c.source["wall_rms_after_mm"] = num(r.wall_rms_after_mm);
  c.logs = o.logs;
  writeLidarOffsetCalibration(o.out, c);
}

void reportHuman(const LidarAxisOffsetCalibRequest& o, const RotatingLidarConfig& rig,
                 const LidarInputs& in, const LidarAxisOffsetResult& r, bool written) {
  std::cerr << std::fixed << std::setprecision(4) << kCalibAxisOffset
            << ": t_L^O' x = " << r.offset_mm.x() << " +- " << r.sigma_x_mm << " mm (the rig's "
            << rig.geometry.lidar_offset_x_mm << " mm)";
  if (r.y_estimated) {
    std::cerr << ", y = " << r.offset_mm.y() << " +- " << r.sigma_y_mm
              << " mm (reported only: the rig's model has none)";
  }
  std::cerr << "\n  from " << in.sweeps_used << " sweeps, " << r.planes.size() << " planes ("
            << r.walls << " walls), " << r.residuals << " residuals, " << r.iterations
            << " iterations" << (r.converged ? "" : " (NOT converged)") << ", "
            << std::setprecision(2) << r.seconds << " s\n"
            << std::setprecision(4) << "  wall-plane RMS " << r.wall_rms_before_mm
            << " mm (before) -> " << r.wall_rms_after_mm << " mm (after); every plane "
            << r.rms_before_mm << " -> " << r.rms_after_mm << " mm; wall inliers ("
            << r.wall_inliers << " points within " << r.cauchy_scale_mm << " mm) "
            << r.wall_inlier_rms_before_mm << " -> " << r.wall_inlier_rms_after_mm << " mm\n"
            << "  observable (mm off the planes per mm, planes adjusted): x "
            << std::setprecision(3) << r.observability.x() << ", y " << r.observability.y()
            << ", z (along the axis) " << r.observability.z() << "\n";
  for (const auto& w : r.warnings) std::cerr << "  warning: " << w << "\n";
  if (in.truth_x_mm) {
    std::cerr << std::setprecision(4) << "  truth x = " << *in.truth_x_mm << " mm: off by "
              << r.offset_mm.x() - *in.truth_x_mm << " mm\n";
  }
  std::cerr << std::setprecision(2) << "  time: sweep assembly " << in.read_s
            << " s, plane segmentation " << in.segment_s << " s, solve " << r.seconds
            << " s, calib rig's joint model (the check) " << in.joint_s << " s\n"
            << "  " << (written ? "wrote " + o.out : std::string("nothing written")) << "\n";
  std::cerr.unsetf(std::ios::floatfield);
}

nlohmann::json resultJson(const LidarAxisOffsetCalibRequest& o, const RotatingLidarConfig& rig,
                          const LidarInputs& in, const LidarAxisOffsetResult& r, bool written) {
  const auto orNull = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; };
  nlohmann::json j;
  j["lidar_offset_x_mm"] = r.offset_mm.x();
  j["sigma_x_mm"] = orNull(r.sigma_x_mm);
  j["nominal_x_mm"] = rig.geometry.lidar_offset_x_mm;
  if (r.y_estimated) {
    j["lidar_offset_y_mm"] = r.offset_mm.y();
    j["sigma_y_mm"] = orNull(r.sigma_y_mm);
  }
  j["observable"] = r.observable;
  j["observability"] = {
      {"x", r.observability.x()}, {"y", r.observability.y()}, {"z", r.observability.z()}};
  j["smallest_singular_value"] = r.smallest_singular_value;
  j["wall_rms_before_mm"] = r.wall_rms_before_mm;
  j["wall_rms_after_mm"] = r.wall_rms_after_mm;
  j["wall_inlier_rms_before_mm"] = r.wall_inlier_rms_before_mm;
  j["wall_inlier_rms_after_mm"] = r.wall_inlier_rms_after_mm;
  j["wall_inliers"] = r.wall_inliers;
  j["rms_before_mm"] = r.rms_before_mm;
  j["rms_after_mm"] = r.rms_after_mm;
  j["cauchy_scale_mm"] = r.cauchy_scale_mm;
  j["iterations"] = r.iterations;
  j["converged"] = r.converged;
  j["residuals"] = r.residuals;
  j["sweeps_used"] = in.sweeps_used;
  j["sweeps_rejected"] = in.rejected;
  j["log_errors"] = in.log_errors;
  j["walls"] = r.walls;
  nlohmann::json planes = nlohmann::json::array();
  for (const auto& p : r.planes) {
    planes.push_back({{"source", p.source},
                      {"rays", p.rays},
                      {"wall", p.wall},
                      {"normal", {p.normal.x(), p.normal.y(), p.normal.z()}},
                      {"distance_mm", p.distance_mm},
                      {"rms_before_mm", p.rms_before_mm},
                      {"rms_after_mm", p.rms_after_mm}});
  }
  j["planes"] = planes;
  j["warnings"] = r.warnings;
  if (in.truth_x_mm) {
    j["truth_x_mm"] = *in.truth_x_mm;
    j["offset_error_mm"] = r.offset_mm.x() - *in.truth_x_mm;
  }
  j["timing_s"] = {{"sweep_assembly", in.read_s},
                   {"segmentation", in.segment_s},
                   {"solve", r.seconds},
                   {"joint_check", in.joint_s}};
  j["out"] = written ? nlohmann::json(o.out) : nullptr;
  return j;
}

}  // namespace

namespace {

// The rig file's scan-plane tilt and mirror offset, which this command holds.
Eigen::Matrix3d lidarRotationOf(const RotatingLidarConfig& rig) {
  return rotating::lidarRotation(rig.geometry.scan_plane_tilt_deg * kDegToRad,
                                 rig.geometry.mirror_offset_deg * kDegToRad);
}

}  // namespace

// The walls' flatness with the estimated offset: their rays' cell medians against their
// planes; a warning into r when they bend more than noise does.
void checkWalls(const RotatingLidarConfig& rig, const LidarInputs& in, LidarAxisOffsetResult* r) {
  std::vector<double> medians;
  const Eigen::Matrix3d R_L = lidarRotationOf(rig);
  for (size_t k = 0; k < in.planes.size() && k < r->planes.size(); ++k) {
    if (!r->planes[k].wall) continue;
    std::vector<Eigen::Vector3f> pts;
    std::vector<int> idx;
    for (const SweepRay& ray : in.planes[k].rays) {
      idx.push_back(static_cast<int>(pts.size()));
      pts.push_back((1e-3 * placeRayMm(ray, r->offset_mm, R_L)).cast<float>());
    }
    const auto m = planeCellMediansMm(pts, idx, r->planes[k].normal,
                                      -1e-3 * r->planes[k].distance_mm, 0.5, 100);
    medians.insert(medians.end(), m.begin(), m.end());
  }
  const std::string w = wallsDisagreeWarning(rmsOf(medians), 2.5);
  if (!w.empty()) r->warnings.push_back(w);
}

// The offset `calib rig`'s joint model gives on the same sweeps (the scan-plane tilt, the
// mirror offset and the plate angle solved with it, clutter on the walls left out): when it
// differs from this fit's by more than 3 sigma, another parameter is off or the walls carry
// clutter that this fit took for them, and a warning into r says so. Takes in->planes.
void checkAgainstJointModel(const RotatingLidarConfig& rig, LidarInputs* in,
                            LidarAxisOffsetResult* r) {
  size_t next = 0;
  for (size_t k = 0; k < in->sweeps.size(); ++k) {
    for (size_t j = 0; j < in->plane_counts[k]; ++j) {
      LidarPlaneRays& p = in->planes[next++];
      stridePlaneRays(kRigCalibPlaneRays, &p);  // as many rays as calib rig keeps
      in->sweeps[k].planes.push_back(std::move(p));
    }
  }
  in->planes.clear();
  const auto t0 = Clock::now();
  const RigCalibration c = solveRigA(in->sweeps, rigASolveOptions(rig));
  in->joint_s = seconds(Clock::now() - t0);
  const auto find = [&](const std::string& key) {
    for (const CalibParameter& p : c.parameters) {
      if (p.key == key && p.observable) return std::optional<CalibParameter>(p);
    }
    return std::optional<CalibParameter>();
  };
  const auto x = find("geometry.lidar_offset_x_mm");
  if (!x) return;
  // As if independent: both come from the same walls, so the difference's sigma is smaller and
  // this errs towards saying nothing.
  const double sigma = std::hypot(x->sigma, r->sigma_x_mm);
  const double z = std::abs(x->value - r->offset_mm.x()) / sigma;
  if (!(z > 3.0)) return;
  std::ostringstream w;
  w << std::fixed << std::setprecision(3) << "calib rig's joint model on these sweeps puts the "
    << "offset at " << x->value << " +- " << x->sigma << " mm, " << std::setprecision(1) << z
    << " sigma from this fit's: another parameter of the rig is off or the walls carry clutter "
       "that this fit took for them";
  for (const char* key : {"geometry.scan_plane_tilt_deg", "geometry.mirror_offset_deg"}) {
    const auto p = find(key);
    if (p && std::abs(p->value - p->nominal) > 3.0 * p->sigma) {
      w << std::setprecision(3) << " (" << key << " " << p->value << " +- " << p->sigma
        << ", the rig's " << p->nominal << ")";
    }
  }
  w << "; run `sweepmap calib rig`";
  r->warnings.push_back(w.str());
}

int calibrateLidarAxisOffsetFromLogs(const LidarAxisOffsetCalibRequest& o) {
  RotatingLidarConfig rig;
  if (!checkInputs(o, &rig)) return kExitUsage;
  LidarInputs in;
  if (!readLogs(o, rig, &in)) return kExitBadInput;
  if (in.planes.empty()) {
    std::cerr << kCalibAxisOffset << ": no sweep with planes in the logs (" << in.rejected.size()
              << " rejected): nothing calibrated\n";
    if (o.json)
      std::cout << nlohmann::json{{"sweeps_used", 0}, {"sweeps_rejected", in.rejected}}.dump(2)
                << "\n";
    return 1;
  }
  LidarAxisOffsetOptions options;
  options.initial_offset_mm = Eigen::Vector3d(rig.geometry.lidar_offset_x_mm, 0.0, 0.0);
  options.lidar_rotation = lidarRotationOf(rig);
  options.estimate_y = o.estimate_y;
  LidarAxisOffsetResult r = solveLidarAxisOffset(in.planes, options);
  checkWalls(rig, in, &r);
  if (r.observable) checkAgainstJointModel(rig, &in, &r);
  bool written = false;
  if (r.observable) {
    try {
      writeCalibration(o, rig, in, r);
      written = true;
    } catch (const std::exception& e) {
      std::cerr << kCalibAxisOffset << ": " << e.what() << "\n";
      return kExitDeviceIo;
    }
  }
  reportHuman(o, rig, in, r, written);
  if (o.json)
    std::cout << std::setprecision(12) << resultJson(o, rig, in, r, written).dump(2) << "\n";
  return written ? 0 : 1;
}

}  // namespace sweepmap
