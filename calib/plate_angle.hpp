// Calibration of the triangular plate's installation angle alpha (Yuan 2021 section 4.2,
// Eq. 11-20, Algorithm A1).
//
// A sweep assembled with plate angle alpha_used relates to the true room by
// C_O(assembled) = R_z(alpha_used - alpha_true) C_O(true) (Eq. 8-10 with phi_offset =
// alpha - beta), so rotating it by (alpha - alpha_used) gives the cloud that plate angle
// alpha would have produced, and its walls line up with i, j at alpha = alpha_true.
// With the sweep's wall normals n_k:
//   f_cost(alpha) = sum_k |R_z(alpha - alpha_used) n_k . a_k|      (Eq. 16-17)
// where a_k = i for a wall whose normal is nearest +-j (n_1, n_3 of Eq. 11) and a_k = j for
// one nearest +-i (n_2, n_4). The class of each normal is decided once, from the normal as
// measured (not rotated), so f_cost does not jump while alpha moves.
// E_atti (Eq. 11) = f_cost(alpha_used). F_cost(alpha) = 1/2 sum_m f_cost(alpha; m)^2 (Eq. 20).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace sweepmap {

struct SweepNormals {
  std::vector<Eigen::Vector3d> normals;  // unit wall normals in the sweep's frame O
  double alpha_used_rad = 0;             // plate angle the sweep was assembled with
};

// f_cost(alpha) of one sweep (Eq. 16).
double fCost(const SweepNormals& s, double alpha_rad);
// d f_cost / d alpha. |x| is not differentiable at 0: a term whose dot product is exactly
// 0 contributes 0 (the subgradient nearest zero); elsewhere sign(x) dx/dalpha.
double fCostDerivative(const SweepNormals& s, double alpha_rad);
// E_atti of Eq. 11: the attitude error of the sweep as assembled.
double attitudeError(const SweepNormals& s);
// F_cost(alpha) of Eq. 20 over all sweeps.
double totalCost(const std::vector<SweepNormals>& sweeps, double alpha_rad);

constexpr double kDefaultAlpha0Rad = 30.0 * 3.14159265358979323846 / 180.0;

// Parameters of Algorithm A1, with its values as defaults.
struct LmOptions {
  double alpha0_rad = kDefaultAlpha0Rad;
  int k_max = 500;
  double eps1 = 1e-9;  // stop when ||g||_inf <= eps1
  double eps2 = 1e-9;  // stop when |step| <= eps2 (|alpha| + eps2)
  double tau = 1e-6;   // mu_0 = tau max(diag(J^T J))
};

struct LmIteration {
  int k = 0;             // iteration; 0 = the initial point
  double alpha_rad = 0;  // alpha after the iteration (unchanged when the step was rejected)
  double cost = 0;       // F_cost(alpha)
  double mu = 0;         // damping after the iteration
};

struct LmResult {
  double alpha_rad = 0;
  int iterations = 0;
  double final_cost = 0;   // F_cost(alpha)
  bool converged = false;  // stopped on eps1 or eps2 (not k_max, not "no data")
  std::string stop_reason;
  std::vector<LmIteration> history;  // k = 0 .. iterations; cost never increases
};

// alpha* = argmin F_cost(alpha) (Eq. 19) by Levenberg-Marquardt, Algorithm A1.
LmResult calibratePlateAngle(const std::vector<SweepNormals>& sweeps,
                             const LmOptions& options = {});

}  // namespace sweepmap
