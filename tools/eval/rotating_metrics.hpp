// Rig A's measures (Yuan 2021 section 5 and Appendix B): every sweep of a log assembled with
// both plate estimators and its walls' deviations (evaluateLog), phi_error statistics per mode
// (phiStats) and the plate angle alpha by LM over the wall normals (calibrateAlpha,
// Algorithm A1). Internal to tools/eval.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "calib/plate_angle.hpp"
#include "core/angles.hpp"
#include "tools/eval/eval_rotating.hpp"
#include "tools/eval/metrics.hpp"

namespace sweepmap::eval {

constexpr double kRefitDistanceM = 0.05;  // ~4 sigma of the UST-10LX range noise

// How a sweep's attitude is corrected: beta by ray_plane (the default), by centroid (the
// paper's), or not at all (C_O').
enum class Method { kRayPlane, kCentroid, kUncorrected };
const char* methodKey(Method m);  // "ray_plane", "centroid", "uncorrected"

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
    return m == Method::kRayPlane ? corrected : m == Method::kCentroid ? corrected_centroid : true;
  }
  // phi_error of the cloud the method publishes (an uncorrected sweep keeps -phi_true).
  std::optional<double> phiErrorRad(Method m) const {
    if (!phi_true_rad) return std::nullopt;
    if (m == Method::kCentroid && !has_centroid) return std::nullopt;
    const double offset = m == Method::kRayPlane ? (corrected ? phi_offset_rad : 0.0)
                          : m == Method::kCentroid
                              ? (corrected_centroid ? phi_offset_centroid_rad : 0.0)
                              : 0.0;
    return wrapAngle(offset - *phi_true_rad);
  }
};

// The sweeps of one mode (or of the naive sequence) and what the figures draw of them.
struct Group {
  std::vector<SweepRecord> sweeps;
  DeviationStats deviations;
  std::vector<Eigen::Vector3f> top_Op, top_O;  // Fig. 8, subsampled
  size_t first_sweep_top_points = 0;           // top_Op points of the first sweep
  std::vector<Eigen::Vector3f> first_sweep_O;  // its whole C_O: the 3D pictures
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

// The rig with plate.beta_method set to each estimator.
struct MethodRigs {
  RotatingLidarConfig ray_plane;
  RotatingLidarConfig centroid;
};
MethodRigs methodRigs(const RotatingLidarConfig& rig);

// Runs the log through the assembler twice (centroid, then ray_plane) and adds a record
// per sweep to the group `group_for(mode)` returns; with `top_views` also the sweep's top
// view points (Fig. 8).
LogStatus evaluateLog(const std::string& path, const std::string& role, const MethodRigs& rigs,
                      const EvalSettings& s, bool top_views,
                      const std::function<Group&(int mode)>& group_for);

// phi_error (deg) over the sweeps a method corrected.
struct PhiStats {
  int sweeps = 0;       // with an error value
  int uncorrected = 0;  // sweeps the method did not correct (left out of the stats)
  double max = 0, mean = 0, min = 0, max_abs = 0;
};
PhiStats phiStats(const std::vector<SweepRecord>& sweeps, Method m);

struct AlphaCalibration {
  bool done = false;
  std::string reason;  // why not done
  int sweeps_used = 0;
  double alpha0_rad = 0.0;
  double e_atti_before = 0.0;  // mean E_atti (Eq. 11) as assembled
  double e_atti_after = 0.0;   // mean f_cost at the calibrated alpha
  LmResult lm;
};

// Algorithm A1 over the wall normals of the sweeps the method corrected.
AlphaCalibration calibrateAlpha(const std::vector<const SweepRecord*>& records, Method method,
                                double alpha0_rad);

}  // namespace sweepmap::eval
