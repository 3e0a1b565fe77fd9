// Rig B's wheels against its gyro: see calib/wheel_gyro_calibration.hpp.
#include "calib/wheel_gyro_calibration.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace sweepmap {
namespace {

struct Row {
  Eigen::Vector3d a;  // (-dphi_L, dphi_R, dt)
  double y;           // the gyro's dtheta
  bool rest;
};

// The gyro's integral from its first sample to `utime` (trapezoids between samples); false
// outside the samples or across a gap longer than `max_gap_us`.
class GyroIntegral {
 public:
  GyroIntegral(const std::vector<GyroReading>& g, int64_t max_gap_us)
      : g_(g), max_gap_(max_gap_us) {
    sum_.resize(g.size(), 0.0);
    for (size_t k = 1; k < g.size(); ++k) {
      sum_[k] = sum_[k - 1] + 0.5 * (g[k - 1].z_rad_s + g[k].z_rad_s) * 1e-6 *
                                  double(g[k].utime - g[k - 1].utime);
    }
  }
  bool at(int64_t utime, double* value) const {
    const auto it = std::upper_bound(g_.begin(), g_.end(), utime,
                                     [](int64_t t, const GyroReading& r) { return t < r.utime; });
    if (it == g_.begin() || it == g_.end()) return false;
    const size_t k = size_t(it - g_.begin()) - 1;
    const double h = 1e-6 * double(g_[k + 1].utime - g_[k].utime);
    if (g_[k + 1].utime - g_[k].utime > max_gap_ || h <= 0) return false;
    const double u = 1e-6 * double(utime - g_[k].utime);
    const double w0 = g_[k].z_rad_s, w1 = g_[k + 1].z_rad_s;
    *value = sum_[k] + w0 * u + 0.5 * (w1 - w0) * u * u / h;
    return true;
  }

 private:
  const std::vector<GyroReading>& g_;
  int64_t max_gap_;
  std::vector<double> sum_;
};

std::vector<Row> windows(const std::vector<WheelReading>& wheels,
                         const std::vector<GyroReading>& gyro, const WheelGyroOptions& o) {
  std::vector<Row> rows;
  if (wheels.size() < 2) return rows;
  const double span_s = 1e-6 * double(wheels.back().utime - wheels.front().utime);
  const double rate = double(wheels.size() - 1) / std::max(span_s, 1e-9);
  const size_t n = std::max<size_t>(1, size_t(std::lround(o.window_s * rate)));
  const GyroIntegral integral(gyro, int64_t(o.max_gyro_gap_s * 1e6));
  const double rad_per_tick = 2.0 * M_PI / o.ticks_per_revolution;
  for (size_t i = 0; i + n < wheels.size(); i += n) {
    const WheelReading &a = wheels[i], &b = wheels[i + n];
    double g0, g1;
    if (b.utime <= a.utime || !integral.at(a.utime, &g0) || !integral.at(b.utime, &g1)) continue;
    Row r;
    const double dl = rad_per_tick * double(b.left - a.left);
    const double dr = rad_per_tick * double(b.right - a.right);
    r.a = Eigen::Vector3d(-dl, dr, 1e-6 * double(b.utime - a.utime));
    r.y = g1 - g0;
    r.rest = std::abs(dl) < o.rest_rad && std::abs(dr) < o.rest_rad;
    rows.push_back(r);
  }
  return rows;
}

// Weighted least squares over the rows `use` marks, each row weighted by its group's sigma
// (standing still: the gyro's noise alone; moving: the encoders' too); false when the normal
// matrix is singular. `normal` is the information matrix.
bool solveRows(const std::vector<Row>& rows, const std::vector<char>& use, const double sigma[2],
               Eigen::Vector3d* x, Eigen::Matrix3d* normal) {
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < rows.size(); ++i) {
    if (!use[i]) continue;
    const double w = 1.0 / (sigma[rows[i].rest] * sigma[rows[i].rest]);
    N += w * rows[i].a * rows[i].a.transpose();
    rhs += w * rows[i].a * rows[i].y;
  }
  if (!N.allFinite() || !rhs.allFinite()) return false;
  // Singular as judged on N with unit diagonal: the bias's entry may outweigh the wheels'
  // by many orders (the windows at rest weigh 1 / sigma^2 with a small sigma).
  const Eigen::Vector3d unit = N.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::LDLT<Eigen::Matrix3d> scaled(unit.asDiagonal() * N * unit.asDiagonal());
  if (scaled.info() != Eigen::Success || !(scaled.vectorD().minCoeff() > 1e-12)) return false;
  *x = unit.asDiagonal() * scaled.solve(unit.asDiagonal() * rhs);
  *normal = N;
  return true;
}

// The least scatter a group is given: 1 urad, far below any real gyro's noise over a window
// (rig B's: about 1 mrad). Noiseless readings (a simulation) fit the windows at rest to
// rounding; their weight would then swamp the wheels' rows.
constexpr double kMinGroupSigmaRad = 1e-6;

// Each group's residual scatter over the rows in use (a group without rows keeps its sigma).
void groupSigmas(const std::vector<Row>& rows, const std::vector<char>& use,
                 const Eigen::Vector3d& x, double sigma[2]) {
  double ss[2] = {0, 0};
  int n[2] = {0, 0};
  for (size_t i = 0; i < rows.size(); ++i) {
    if (!use[i]) continue;
    const double r = rows[i].y - rows[i].a.dot(x);
    ss[rows[i].rest] += r * r;
    ++n[rows[i].rest];
  }
  // Three parameters shared out by the groups' sizes.
  const double total = std::max(1, n[0] + n[1]);
  for (int g = 0; g < 2; ++g) {
    const double dof = n[g] - 3.0 * n[g] / total;
    if (dof > 1.0) sigma[g] = std::max(kMinGroupSigmaRad, std::sqrt(ss[g] / dof));
  }
}

}  // namespace

WheelGyroResult calibrateWheelsAgainstGyro(const std::vector<WheelReading>& wheels,
                                           const std::vector<GyroReading>& gyro,
                                           const WheelGyroOptions& o) {
  WheelGyroResult out;
  const std::vector<Row> rows = windows(wheels, gyro, o);
  std::vector<char> use(rows.size(), 1);
  Eigen::Matrix3d N;
  double sigma[2] = {1.0, 1.0};  // moving, standing still
  for (int it = 0; it <= o.trim_iterations; ++it) {
    if (!solveRows(rows, use, sigma, &out.x, &N)) {
      out.reason = "the drive's windows do not determine both wheels and the gyro bias (" +
                   std::to_string(rows.size()) + " windows; turns both ways and stops needed)";
      return out;
    }
    // Each group's scatter, then every row judged against it (a trimmed row may come back).
    const double before[2] = {sigma[0], sigma[1]};
    groupSigmas(rows, use, out.x, sigma);
    bool changed =
        std::abs(sigma[0] / before[0] - 1) > 0.01 || std::abs(sigma[1] / before[1] - 1) > 0.01;
    for (size_t i = 0; i < rows.size(); ++i) {
      const bool keep =
          std::abs(rows[i].y - rows[i].a.dot(out.x)) <= o.trim_sigma * sigma[rows[i].rest];
      changed = changed || keep != bool(use[i]);
      use[i] = keep;
    }
    if (!changed) break;
  }
  if (!solveRows(rows, use, sigma, &out.x, &N)) {
    out.reason = "too few windows left after trimming the outliers";
    return out;
  }
  out.covariance = N.inverse();
  for (int k = 0; k < 2; ++k) {
    const double relative = std::sqrt(out.covariance(k, k)) / std::abs(out.x(k));
    if (!(relative <= o.max_relative_sigma)) {
      out.reason = "the drive determines the wheels' ratio to the track only to " +
                   std::to_string(relative) +
                   " (relative; turns both ways, straights and stops needed)";
      return out;
    }
  }
  out.ok = true;
  for (size_t i = 0; i < rows.size(); ++i) {
    out.rows += use[i];
    out.rest_rows += use[i] && rows[i].rest;
  }
  out.trimmed = int(rows.size()) - out.rows;
  out.sigma_rad = sigma[0];
  return out;
}

}  // namespace sweepmap
