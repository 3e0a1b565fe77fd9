// The rig-neutral part of `sweepmap calib rig`: the table of calibrated parameters (keyed by
// the rig file's keys), their correlation, which of them the logs made observable, and the
// outputs (calibration file, JSON, human report). Each rig kind's solver (rig A:
// calib/rig_a_calibration.hpp) fills a RigCalibration from its covariance.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/calibration_file.hpp"

namespace sweepmap {

struct CalibParameter {
  std::string key;  // the rig file's key, e.g. plate.alpha_deg
  double value = 0.0;
  double sigma = 0.0;  // 1 sigma, from the covariance; NaN when not observable
  std::string unit;
  bool observable = true;       // false: reported, left at `nominal`, not written
  std::optional<double> truth;  // simulated logs only
  double nominal = 0.0;         // the rig's value before calibration
  std::string note;             // why not observable
};

// What the calibrated data measure, to compare with a known value (rig B: the room's size).
struct CalibMeasure {
  std::string key;  // e.g. room.length_m
  double value = 0.0;
  std::string unit;
  std::optional<double> truth;  // simulated logs: the scene's
  std::optional<double> sigma;  // its 1-sigma uncertainty, where known
};

struct RigCalibration {
  std::vector<CalibParameter> parameters;
  std::vector<CalibMeasure> measures;  // JSON "measures": {"<key>": {"value", "unit", "truth"?}}
  Eigen::MatrixXd correlation;         // of `parameters`, in their order
  double rms_before = 0.0;             // residual RMS with the rig's values (residual_unit)
  double rms_after = 0.0;
  std::vector<std::string> warnings;
  std::string residual_unit = "mm";
  int sweeps_used = 0;
  std::vector<std::string> rejected;  // "SOURCE: why"
  double seconds = 0.0;               // the solve
};

// Limits of the observability test of one parameter: its sigma must not exceed max_sigma.
struct ObservabilityLimits {
  std::vector<double> max_sigma;  // per parameter, in its unit
  double min_eigenvalue = 1e-6;   // of the correlation matrix: below, a combination is lost
};

// Correlation matrix of a covariance (0 where a variance is 0 or not finite).
Eigen::MatrixXd correlationOf(const Eigen::MatrixXd& covariance);

// Sets sigma, observable and note of every parameter from the covariance (parameters' units):
// a parameter is unobservable when its sigma exceeds its limit, when it is not finite, or when
// it carries the most weight of a correlation eigenvector whose eigenvalue is below the limit
// (the logs determine only a combination of it with others). Returns the indices flagged.
std::vector<size_t> testObservability(const Eigen::MatrixXd& covariance,
                                      const ObservabilityLimits& limits,
                                      std::vector<CalibParameter>* parameters);

// {"parameters": {"<key>": {"value", "sigma", "unit", "observable", "truth"?}}, "warnings": [...],
//  "correlation": {"keys": [...], "matrix": [[...]]}, "rms_before", "rms_after", ...}
nlohmann::json rigCalibrationJson(const RigCalibration& c);

// The calibration file: the observable parameters (the others stay as the rig has them), with
// each one's sigma and the residuals under `source`.
RigCalibrationFile rigCalibrationFile(const RigCalibration& c, const std::string& tool,
                                      const std::vector<std::string>& logs);

// Medians [mm] of the residuals normal . p + offset_m of cloud[idx] over square cells of
// `cell_m` on the (near vertical) plane, along it and up; cells with fewer than `min_points`
// are left out. Noise alone scatters them by ~1.25 sigma / sqrt(points per cell); a rig
// parameter that is off bends the plane and scatters them more.
std::vector<double> planeCellMediansMm(const std::vector<Eigen::Vector3f>& cloud,
                                       const std::vector<int>& idx, const Eigen::Vector3d& normal,
                                       double offset_m, double cell_m, size_t min_points);
double rmsOf(const std::vector<double>& values);

// The single-parameter commands' warning when the walls' cell medians scatter by `rms_mm` over
// `limit_mm` (empty when they do not).
std::string wallsDisagreeWarning(double rms_mm, double limit_mm);

// A few lines per parameter (value +- sigma, truth, observable), the residuals, the warnings.
std::string rigCalibrationReport(const RigCalibration& c);

}  // namespace sweepmap
