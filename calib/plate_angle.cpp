#include "calib/plate_angle.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace sweepmap {
namespace {

// Dot products of R_z(delta) n with i and j.
struct Projections {
  double on_i, on_j;
};
Projections project(const Eigen::Vector3d& n, double delta) {
  const double c = std::cos(delta), s = std::sin(delta);
  return {c * n.x() - s * n.y(), s * n.x() + c * n.y()};
}

// A wall whose normal is nearest +-j must be perpendicular to i (n_1, n_3 of Eq. 11).
bool perpendicularToI(const Eigen::Vector3d& n) { return std::abs(n.y()) >= std::abs(n.x()); }

double sign(double x) { return x > 0 ? 1.0 : (x < 0 ? -1.0 : 0.0); }

}  // namespace

double fCost(const SweepNormals& s, double alpha_rad) {
  const double delta = alpha_rad - s.alpha_used_rad;
  double f = 0;
  for (const auto& n : s.normals) {
    const Projections p = project(n, delta);
    f += std::abs(perpendicularToI(n) ? p.on_i : p.on_j);
  }
  return f;
}

double fCostDerivative(const SweepNormals& s, double alpha_rad) {
  const double delta = alpha_rad - s.alpha_used_rad;
  double df = 0;
  for (const auto& n : s.normals) {
    const Projections p = project(n, delta);
    // d/d delta (R n . i) = -(R n . j);  d/d delta (R n . j) = R n . i.
    df += perpendicularToI(n) ? sign(p.on_i) * -p.on_j : sign(p.on_j) * p.on_i;
  }
  return df;
}

double attitudeError(const SweepNormals& s) { return fCost(s, s.alpha_used_rad); }

double totalCost(const std::vector<SweepNormals>& sweeps, double alpha_rad) {
  double F = 0;
  for (const auto& s : sweeps) {
    const double f = fCost(s, alpha_rad);
    F += f * f;
  }
  return 0.5 * F;
}

// Algorithm A1 (Madsen, Nielsen & Tingleff, "Methods for non-linear least squares
// problems", Algorithm 3.16) for the one parameter alpha, written out rather than run
// through Ceres: the calibration must report the paper's own parameters (tau, eps1, eps2,
// k_max, nu) and the per-iteration history (alpha, cost, mu), and Ceres' trust-region LM
// has a different damping update and stopping rules, none of which can be set to A1's.
// The residual of sweep m is f_cost(alpha; m) itself, its derivative analytic (see
// fCostDerivative), so A = J^T J and g = J^T f are sums over the sweeps.
LmResult calibratePlateAngle(const std::vector<SweepNormals>& sweeps, const LmOptions& o) {
  LmResult r;
  double alpha = o.alpha0_rad;
  const auto evaluate = [&](double a, double* A, double* g) {
    *A = 0;
    *g = 0;
    for (const auto& s : sweeps) {
      const double f = fCost(s, a);
      const double J = fCostDerivative(s, a);
      *A += J * J;
      *g += J * f;
    }
  };
  double F = totalCost(sweeps, alpha);
  r.alpha_rad = alpha;
  r.final_cost = F;
  if (sweeps.empty()) {
    r.stop_reason = "no sweeps";
    return r;
  }
  double A = 0, g = 0;
  evaluate(alpha, &A, &g);
  double mu = o.tau * A;  // max{a_ii} of a 1x1 matrix
  double nu = 2;
  r.history.push_back({0, alpha, F, mu});
  bool found = std::abs(g) <= o.eps1;
  if (found) r.stop_reason = "gradient ||g||inf <= eps1";
  int k = 0;
  while (!found && k < o.k_max) {
    ++k;
    if (A + mu <= 0) {  // J = 0 with g != 0 cannot happen; guard the division anyway
      r.stop_reason = "singular: J^T J + mu = 0";
      break;
    }
    const double h = -g / (A + mu);
    if (std::abs(h) <= o.eps2 * (std::abs(alpha) + o.eps2)) {
      found = true;
      r.stop_reason = "step |h| <= eps2 (|alpha| + eps2)";
    } else {
      const double alpha_new = alpha + h;
      const double F_new = totalCost(sweeps, alpha_new);
      // Gain ratio: actual over predicted decrease, L(0) - L(h) = 1/2 h (mu h - g) > 0.
      const double predicted = 0.5 * h * (mu * h - g);
      const double rho = predicted > 0 ? (F - F_new) / predicted : -1.0;
      if (rho > 0) {
        alpha = alpha_new;
        F = F_new;
        evaluate(alpha, &A, &g);
        found = std::abs(g) <= o.eps1;
        if (found) r.stop_reason = "gradient ||g||inf <= eps1";
        mu *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
        nu = 2;
      } else {
        mu *= nu;
        nu *= 2;
      }
    }
    r.history.push_back({k, alpha, F, mu});
    // mu overflowing means no step decreases F any more: as good as converged on step size.
    if (!found && !std::isfinite(mu)) {
      found = true;
      r.stop_reason = "damping overflow (no decreasing step)";
    }
  }
  if (!found && r.stop_reason.empty()) r.stop_reason = "k_max iterations reached";
  r.alpha_rad = alpha;
  r.iterations = k;
  r.final_cost = F;
  r.converged = found;
  return r;
}

}  // namespace sweepmap
