#include "calib/parameter_information.hpp"

#include <ceres/crs_matrix.h>

#include <Eigen/Dense>
#include <limits>

namespace sweepmap {
namespace {

// J^T J of the CRS Jacobian, summed row by row in the rows' order.
Eigen::MatrixXd normalMatrix(const ceres::CRSMatrix& j) {
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(j.num_cols, j.num_cols);
  for (int r = 0; r < j.num_rows; ++r) {
    for (int a = j.rows[size_t(r)]; a < j.rows[size_t(r) + 1]; ++a) {
      const double va = j.values[size_t(a)];
      if (va == 0.0) continue;
      for (int b = a; b < j.rows[size_t(r) + 1]; ++b) {
        h(j.cols[size_t(a)], j.cols[size_t(b)]) += va * j.values[size_t(b)];
      }
    }
  }
  // Columns within a row need not ascend: fold both triangles into one, then mirror it.
  const Eigen::MatrixXd upper = h.triangularView<Eigen::StrictlyUpper>();
  const Eigen::MatrixXd lower = h.triangularView<Eigen::StrictlyLower>();
  Eigen::MatrixXd s = upper + lower.transpose();
  s.diagonal() = h.diagonal();
  return s.selfadjointView<Eigen::Upper>();
}

}  // namespace

ParameterInformation eliminatedInformation(ceres::Problem* problem,
                                           const std::vector<double*>& nuisance,
                                           const std::vector<double*>& parameters) {
  ParameterInformation out;
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = nuisance;
  eo.parameter_blocks.insert(eo.parameter_blocks.end(), parameters.begin(), parameters.end());
  eo.num_threads = 1;
  Eigen::Index k = 0;
  for (double* p : parameters) k += problem->ParameterBlockTangentSize(p);
  ceres::CRSMatrix j;
  if (k == 0 || !problem->Evaluate(eo, nullptr, nullptr, nullptr, &j)) return out;
  const Eigen::MatrixXd h = normalMatrix(j);
  const Eigen::Index rest = h.rows() - k;
  // Every column to unit length: the units (mm, rad) then leave the elimination's rounding alone.
  Eigen::VectorXd d = h.diagonal().cwiseSqrt();
  for (Eigen::Index i = 0; i < d.size(); ++i) {
    if (!(d(i) > 0.0)) d(i) = 1.0;
  }
  const Eigen::VectorXd inv = d.cwiseInverse();
  const Eigen::MatrixXd hs = inv.asDiagonal() * h * inv.asDiagonal();
  Eigen::MatrixXd schur = hs.bottomRightCorner(k, k);
  if (rest > 0) {
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(hs.topLeftCorner(rest, rest));
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return out;
    schur -= hs.bottomLeftCorner(k, rest) * ldlt.solve(hs.topRightCorner(rest, k));
  }
  const Eigen::VectorXd dp = d.tail(k);
  out.information = dp.asDiagonal() * schur * dp.asDiagonal();
  out.information = (0.5 * (out.information + out.information.transpose())).eval();
  out.column_norms = h.diagonal().tail(k).cwiseSqrt();
  out.ok = out.information.allFinite();
  return out;
}

Eigen::MatrixXd covarianceFromInformation(const Eigen::MatrixXd& information) {
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(information);
  if (information.size() == 0 || !information.allFinite() || !lu.isInvertible()) {
    return Eigen::MatrixXd::Constant(information.rows(), information.cols(),
                                     std::numeric_limits<double>::quiet_NaN());
  }
  return lu.inverse();
}

Eigen::MatrixXd scaledInformation(const ParameterInformation& info) {
  Eigen::MatrixXd s = info.information;
  for (Eigen::Index i = 0; i < s.rows(); ++i) {
    for (Eigen::Index c = 0; c < s.cols(); ++c) {
      const double n = info.column_norms(i) * info.column_norms(c);
      s(i, c) = n > 0 ? s(i, c) / n : 0.0;
    }
  }
  return s;
}

}  // namespace sweepmap
