#include "calib/rig_calibration.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

namespace sweepmap {
namespace {

std::string num(double v, int precision = 6) {
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

nlohmann::json orNull(double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; }

}  // namespace

Eigen::MatrixXd correlationOf(const Eigen::MatrixXd& c) {
  const Eigen::Index n = c.rows();
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      const double d = std::sqrt(c(i, i) * c(j, j));
      r(i, j) = std::isfinite(d) && d > 0 ? c(i, j) / d : (i == j ? 1.0 : 0.0);
    }
  }
  return r;
}

std::vector<size_t> testObservability(const Eigen::MatrixXd& covariance,
                                      const ObservabilityLimits& limits,
                                      std::vector<CalibParameter>* params) {
  std::vector<size_t> flagged;
  const auto flag = [&](size_t i, const std::string& why) {
    CalibParameter& p = (*params)[i];
    if (!p.observable) return;
    p.observable = false;
    p.note = why;
    flagged.push_back(i);
  };
  for (size_t i = 0; i < params->size(); ++i) {
    const double var = covariance(Eigen::Index(i), Eigen::Index(i));
    (*params)[i].sigma = std::sqrt(var);
    if (!std::isfinite(var) || var < 0) {
      flag(i, "the covariance has no finite variance for it");
    } else if (i < limits.max_sigma.size() && (*params)[i].sigma > limits.max_sigma[i]) {
      flag(i, "sigma " + num((*params)[i].sigma, 3) + " " + (*params)[i].unit + " > " +
                  num(limits.max_sigma[i], 3) + ": the logs do not determine it");
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(correlationOf(covariance));
  if (eig.info() == Eigen::Success) {
    for (Eigen::Index k = 0; k < eig.eigenvalues().size(); ++k) {
      if (eig.eigenvalues()(k) >= limits.min_eigenvalue) continue;
      Eigen::Index worst = 0;
      eig.eigenvectors().col(k).cwiseAbs().maxCoeff(&worst);
      flag(size_t(worst),
           "only a combination with the others is determined (correlation "
           "eigenvalue " +
               num(eig.eigenvalues()(k), 3) + ")");
    }
  }
  return flagged;
}

nlohmann::json rigCalibrationJson(const RigCalibration& c) {
  nlohmann::json params = nlohmann::json::object();
  nlohmann::json keys = nlohmann::json::array();
  for (const auto& p : c.parameters) {
    nlohmann::json j = {{"value", p.value},
                        {"sigma", orNull(p.sigma)},
                        {"unit", p.unit},
                        {"observable", p.observable},
                        {"nominal", p.nominal}};
    if (p.truth) {
      j["truth"] = *p.truth;
      j["error"] = p.value - *p.truth;
    }
    if (!p.note.empty()) j["note"] = p.note;
    params[p.key] = j;
    keys.push_back(p.key);
  }
  nlohmann::json matrix = nlohmann::json::array();
  for (Eigen::Index i = 0; i < c.correlation.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index j = 0; j < c.correlation.cols(); ++j)
      row.push_back(orNull(c.correlation(i, j)));
    matrix.push_back(row);
  }
  nlohmann::json measures = nlohmann::json::object();
  for (const auto& m : c.measures) {
    nlohmann::json j = {{"value", m.value}, {"unit", m.unit}};
    if (m.sigma) j["sigma"] = *m.sigma;
    if (m.truth) {
      j["truth"] = *m.truth;
      j["error"] = m.value - *m.truth;
    }
    measures[m.key] = j;
  }
  return {{"parameters", params},
          {"measures", measures},
          {"warnings", c.warnings},
          {"correlation", {{"keys", keys}, {"matrix", matrix}}},
          {"residuals",
           {{"unit", c.residual_unit}, {"rms_before", c.rms_before}, {"rms_after", c.rms_after}}},
          {"sweeps_used", c.sweeps_used},
          {"sweeps_rejected", c.rejected},
          {"solve_s", c.seconds}};
}

RigCalibrationFile rigCalibrationFile(const RigCalibration& c, const std::string& tool,
                                      const std::vector<std::string>& logs) {
  RigCalibrationFile f;
  for (const auto& p : c.parameters) {
    if (!p.observable) {
      f.source["not_observable." + p.key] = p.note;
      continue;
    }
    f.parameters.emplace_back(p.key, p.value);
    f.source["sigma." + p.key] = num(p.sigma);
  }
  f.source["tool"] = tool;
  if (c.sweeps_used > 0) f.source["sweeps"] = std::to_string(c.sweeps_used);
  f.source["rms_before_" + c.residual_unit] = num(c.rms_before);
  f.source["rms_after_" + c.residual_unit] = num(c.rms_after);
  f.logs = logs;
  return f;
}

std::vector<double> planeCellMediansMm(const std::vector<Eigen::Vector3f>& cloud,
                                       const std::vector<int>& idx, const Eigen::Vector3d& n,
                                       double offset_m, double cell_m, size_t min_points) {
  std::map<std::pair<long, long>, std::vector<double>> cells;
  const Eigen::Vector2d along = Eigen::Vector2d(-n.y(), n.x()).normalized();
  for (const int i : idx) {
    const Eigen::Vector3d p = cloud[size_t(i)].cast<double>();
    cells[{long(std::floor(along.dot(p.head<2>()) / cell_m)), long(std::floor(p.z() / cell_m))}]
        .push_back(1e3 * (n.dot(p) + offset_m));
  }
  std::vector<double> medians;
  for (auto& [cell, e] : cells) {
    if (e.size() < min_points) continue;
    std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
    medians.push_back(e[e.size() / 2]);
  }
  return medians;
}

double rmsOf(const std::vector<double>& v) {
  double ss = 0.0;
  for (const double x : v) ss += x * x;
  return v.empty() ? 0.0 : std::sqrt(ss / double(v.size()));
}

std::string wallsDisagreeWarning(double rms_mm, double limit_mm) {
  if (!(rms_mm > limit_mm)) return "";
  return "the walls disagree with their planes by " + num(rms_mm, 3) +
         " mm RMS over 0.5 m cells, more than the noise (" + num(limit_mm, 3) +
         " mm): another parameter of the rig is off (scan-plane tilt, mirror offset, offset), or "
         "something stands proud of a wall (a whiteboard, a shelf); run `sweepmap calib rig`, "
         "which solves them all and leaves such cells out";
}

std::string rigCalibrationReport(const RigCalibration& c) {
  std::ostringstream s;
  for (const auto& p : c.parameters) {
    s << "  " << std::left << std::setw(30) << p.key << std::right << std::fixed
      << std::setprecision(4) << std::setw(10) << p.value << " +- " << std::setprecision(4)
      << p.sigma << " " << p.unit << " (rig: " << p.nominal << ")";
    if (p.truth) s << ", truth " << *p.truth << ", off by " << p.value - *p.truth;
    if (!p.observable) s << "\n    NOT observable, left at the rig's value: " << p.note;
    s << "\n";
  }
  s << std::setprecision(3) << "  residual RMS " << c.rms_before << " " << c.residual_unit
    << " with the rig's values -> " << c.rms_after << " " << c.residual_unit << " calibrated\n";
  if (c.correlation.rows() > 1) {
    s << "  correlation:";
    for (Eigen::Index i = 0; i < c.correlation.rows(); ++i) {
      s << (i ? "; " : " ");
      for (Eigen::Index j = 0; j < c.correlation.cols(); ++j) {
        s << (j ? " " : "") << std::setprecision(2) << c.correlation(i, j);
      }
    }
    s << "\n";
  }
  for (const auto& m : c.measures) {
    s << "  measured " << m.key << " " << std::fixed << std::setprecision(6) << m.value;
    if (m.sigma) s << " +- " << std::setprecision(4) << *m.sigma;
    s << " " << m.unit;
    if (m.truth) {
      s << ", truth " << std::setprecision(6) << *m.truth << ", off by " << std::setprecision(4)
        << m.value - *m.truth;
    }
    s << "\n";
  }
  for (const auto& w : c.warnings) s << "  warning: " << w << "\n";
  return s.str();
}

}  // namespace sweepmap
