// The uncertainty of a least squares' parameters of interest with its nuisance parameters
// (planes, per-sweep attitudes) eliminated, in a fixed order: every calibration's sigma and
// observability test (rig A's `calib rig`, rig A's `calib axis-offset`, rig C's axis offsets).
//
// Not ceres::Covariance: it orders the parameter blocks by their memory addresses, so the sums
// of its factorisation, and the sigmas' last digits, changed from run to run. Here the
// Jacobian's columns come in the order the caller gives, its rows in the problem's order, and
// J^T J is summed row by row in that order, then the nuisance block is eliminated (Schur
// complement, after scaling every column to unit length) with one thread: the same problem
// gives the same bytes whatever the machine.
//
// Internal to the calib library (it needs Ceres, which stays private to it).
#pragma once

#include <ceres/problem.h>

#include <Eigen/Core>
#include <vector>

namespace sweepmap {

struct ParameterInformation {
  bool ok = false;  // false: the Jacobian could not be evaluated or the nuisance is singular
  // J^T J of the parameters' tangent coordinates (in the given blocks' order) with the
  // nuisance eliminated: its inverse is their covariance per unit residual variance.
  Eigen::MatrixXd information;
  // The norms of the parameters' Jacobian columns before the elimination: the information
  // scaled by them tells how much of what the data say about a parameter is left once the
  // nuisance has taken its share (1: none taken, 0: none left).
  Eigen::VectorXd column_norms;
};

// From the problem's Jacobian at its current values (robust losses applied, tangent spaces of
// the manifolds). Every block given must be a variable block of the problem; blocks the
// problem holds but not given are held at their values.
ParameterInformation eliminatedInformation(ceres::Problem* problem,
                                           const std::vector<double*>& nuisance,
                                           const std::vector<double*>& parameters);

// The inverse of an information matrix; every entry NaN when it is singular.
Eigen::MatrixXd covarianceFromInformation(const Eigen::MatrixXd& information);

// The information scaled by the column norms (unit diagonal when nothing was eliminated).
Eigen::MatrixXd scaledInformation(const ParameterInformation& info);

}  // namespace sweepmap
