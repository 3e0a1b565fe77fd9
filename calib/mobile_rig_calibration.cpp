// Rig B's joint calibration: see calib/mobile_rig_calibration.hpp.
#include "calib/mobile_rig_calibration.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "calib/overlap_alignment.hpp"

namespace sweepmap {
namespace {

using M = MobileOverlapModel;
// The wheel parameters' entries of the joint vector: changes of the left and right radii and
// of the track width from the odometry run's.
constexpr int kRadiusLeft = M::kFirstOdometry, kRadiusRight = M::kFirstOdometry + 1,
              kTrack = M::kFirstOdometry + 2, kParameters = M::kFirstOdometry + 3;

// A parameter is observable when the drive determines it better than this (1 sigma): beyond,
// it is held at nominal and reported unobservable.
double observabilityBound(int k) {
  switch (k) {
    case M::kGamma:
    case M::kBeta:
    case M::kAlpha:
      return 3e-3;  // rad
    case M::kTimeOffset:
      return 0.02;  // s
    case M::kLeverX:
    case M::kLeverY:
    case M::kLeverZ:
      return 0.01;  // m
    case kRadiusLeft:
    case kRadiusRight:
      return 3e-4;  // m (1 % of a 32.5 mm wheel)
    case kTrack:
      return 0.01;  // m
    default:
      return 0.0;
  }
}

// The tracks of the odometry with each wheel parameter moved by its step: the model's
// sensitivities.
struct Sensitivities {
  MobileOdometryRun base;
  PoseTrack moved[3];
  double step[3] = {1e-4, 1e-4, 1e-3};
};

void runOdometry(const MobileRigCalibrationInput& in, const MobileWheelParameters& w,
                 Sensitivities* s) {
  s->base = in.odometry(w);
  for (int k = 0; k < 3; ++k) {
    MobileWheelParameters p = w;
    (k == 0 ? p.radius_left_m : k == 1 ? p.radius_right_m : p.wheel_distance_m) += s->step[k];
    s->moved[k] = in.odometry(p).track;
  }
}

// One joint solve from x over `free`; the held parameters keep their values in x.
OverlapResult solve(const std::vector<OverlapRay>& rays, M& model, const Eigen::VectorXd& x,
                    const std::vector<bool>& free, const MobileRigCalibrationInput& in) {
  OverlapOptions oo;
  oo.base = in.options;
  oo.free = free;
  oo.lower = Eigen::VectorXd::Constant(kParameters, -1e300);
  oo.upper = Eigen::VectorXd::Constant(kParameters, 1e300);
  oo.lower(M::kTimeOffset) = -in.options.max_time_offset_s;
  oo.upper(M::kTimeOffset) = in.options.max_time_offset_s;
  oo.threads = in.options.threads;
  return alignOverlap(rays, model, x, oo);
}

// The covariance of the parameters in `set` from the information matrix; false if singular.
bool covarianceOf(const Eigen::MatrixXd& info, const std::vector<int>& set, Eigen::MatrixXd* cov) {
  const int F = int(set.size());
  Eigen::MatrixXd H(F, F);
  for (int i = 0; i < F; ++i) {
    for (int j = 0; j < F; ++j) H(i, j) = info(set[size_t(i)], set[size_t(j)]);
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(H);
  if (!lu.isInvertible()) return false;
  *cov = lu.inverse();
  return true;
}

// Stated order: the mounting angles first (always observable on a drive that sees the same
// surfaces twice), then each other parameter in turn, kept when the drive determines it
// within its bound without more than doubling the sigma of any parameter already kept
// (judged on the information matrix of the angles' solution, no solve per candidate).
// Then one joint solve over the kept ones.
OverlapResult solveObservable(const std::vector<OverlapRay>& rays, M& model,
                              const Eigen::VectorXd& x, const MobileRigCalibrationInput& in,
                              std::vector<bool>* free) {
  std::vector<bool> angles(size_t(kParameters), false);
  for (int k : {M::kGamma, M::kBeta, M::kAlpha}) angles[size_t(k)] = true;
  const OverlapResult first = solve(rays, model, x, angles, in);
  if (!first.ok) return first;
  std::vector<int> kept = {M::kGamma, M::kBeta, M::kAlpha};
  Eigen::MatrixXd cov;
  if (!covarianceOf(first.information, kept, &cov)) return first;
  const int order[] = {M::kTimeOffset, M::kLeverX,   M::kLeverY, M::kLeverZ,
                       kRadiusLeft,    kRadiusRight, kTrack};
  for (int k : order) {
    if (!(*free)[size_t(k)]) continue;
    std::vector<int> trial = kept;
    trial.push_back(k);
    Eigen::MatrixXd c;
    bool ok = covarianceOf(first.information, trial, &c) &&
              std::sqrt(std::max(0.0, c(int(trial.size()) - 1, int(trial.size()) - 1))) <=
                  observabilityBound(k);
    for (size_t i = 0; ok && i < kept.size(); ++i) {
      ok = c(int(i), int(i)) <= 4.0 * cov(int(i), int(i));
    }
    if (ok) {
      kept = trial;
      cov = c;
    }
  }
  std::fill(free->begin(), free->end(), false);
  for (int k : kept) (*free)[size_t(k)] = true;
  return solve(rays, model, first.x, *free, in);
}

RigCalibration report(const MobileRigCalibrationInput& in, const Eigen::VectorXd& x,
                      const MobileWheelParameters& w, const OverlapResult& r,
                      const std::vector<bool>& free, const MobileOdometryRun& odo,
                      double rms_before) {
  RigCalibration out;
  const LidarMounting& n = in.nominal;
  struct Row {
    const char* key;
    const char* unit;
    double value;
    int index;       // into x (-1: not in the joint solve)
    double nominal;  // the rig file's (the start)
  };
  const MobileWheelParameters& w0 = in.wheels;
  const Row rows[] = {
      {"mounting.gamma_rad", "rad", x(M::kGamma), M::kGamma, n.gamma_rad},
      {"mounting.beta_rad", "rad", x(M::kBeta), M::kBeta, n.beta_rad},
      {"mounting.alpha_rad", "rad", x(M::kAlpha), M::kAlpha, n.alpha_rad},
      {"mounting.x_m", "m", n.t_BL_m.x() + x(M::kLeverX), M::kLeverX, n.t_BL_m.x()},
      {"mounting.y_m", "m", n.t_BL_m.y() + x(M::kLeverY), M::kLeverY, n.t_BL_m.y()},
      {"mounting.z_m", "m", n.t_BL_m.z() + x(M::kLeverZ), M::kLeverZ, n.t_BL_m.z()},
      {"odometry.wheel_radius_m", "m", w.radius_left_m, kRadiusLeft, w0.radius_left_m},
      {"odometry.wheel_radius_right_m", "m", w.radius_right_m, kRadiusRight, w0.radius_right_m},
      {"odometry.wheel_distance_m", "m", w.wheel_distance_m, kTrack, w0.wheel_distance_m},
      {"lidar.time_offset_s", "s", -x(M::kTimeOffset), M::kTimeOffset, 0.0},
  };
  std::vector<int> index;
  for (const Row& row : rows) {
    CalibParameter p;
    p.key = row.key;
    p.unit = row.unit;
    p.value = row.value;
    p.nominal = row.nominal;
    p.observable = free[size_t(row.index)];
    if (!p.observable) p.note = "its sigma exceeds its bound on this drive";
    p.sigma = p.observable ? std::sqrt(std::max(0.0, r.covariance(row.index, row.index))) : 0.0;
    const auto t = in.truth.find(p.key);
    if (t != in.truth.end()) p.truth = t->second;
    out.parameters.push_back(p);
    index.push_back(row.index);
  }
  CalibParameter bias{"odometry.gyro_bias_rad_s",
                      odo.gyro_bias_rad_s,
                      odo.gyro_bias_sigma_rad_s,
                      "rad/s",
                      true,
                      std::nullopt};
  const auto t = in.truth.find(bias.key);
  if (t != in.truth.end()) bias.truth = t->second;
  out.parameters.push_back(bias);
  // Correlations of the joint solve (the gyro bias comes from the EKF: 0 with the others).
  const int N = int(out.parameters.size());
  out.correlation = Eigen::MatrixXd::Identity(N, N);
  for (int i = 0; i + 1 < N; ++i) {
    for (int j = 0; j + 1 < N; ++j) {
      const double si = out.parameters[size_t(i)].sigma, sj = out.parameters[size_t(j)].sigma;
      if (i != j && si > 0 && sj > 0)
        out.correlation(i, j) = r.covariance(index[size_t(i)], index[size_t(j)]) / (si * sj);
    }
  }
  out.rms_before = rms_before;
  out.rms_after = r.residual_after_m;
  for (const CalibParameter& p : out.parameters) {
    if (!p.observable)
      out.warnings.push_back(p.key + ": not observable from these logs; left at the rig file's");
  }
  if (r.chi2_per_dof > 4.0) {
    out.warnings.push_back("the residuals are larger than the lidar's noise explains (chi2/dof " +
                           std::to_string(r.chi2_per_dof) +
                           "): an error the model does not have (moving objects, "
                           "a wrong noise figure, slip) may bias the result");
  }
  if (free[M::kTimeOffset] && std::abs(x(M::kTimeOffset)) >= 0.99 * in.options.max_time_offset_s) {
    out.warnings.push_back("lidar.time_offset_s ran to its bound: the drive does not observe it");
  }
  return out;
}

}  // namespace

RigCalibration calibrateMobileRig(const MobileRigCalibrationInput& in) {
  const std::vector<OverlapRay> rays =
      overlapRays(in.scans, in.nominal.nominal_rpy_rad, std::max(1, in.options.ray_stride));
  MobileWheelParameters w = in.wheels;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(kParameters);
  x(M::kGamma) = in.nominal.gamma_rad;
  x(M::kBeta) = in.nominal.beta_rad;
  x(M::kAlpha) = in.nominal.alpha_rad;
  std::vector<bool> free(size_t(kParameters), true);
  free[M::kDriftX] = free[M::kDriftY] = false;  // the wheels explain the track's drift
  OverlapResult r;
  Sensitivities s;
  double rms_before = 0.0;
  constexpr int kPasses = 2;
  for (int pass = 0; pass < kPasses; ++pass) {
    if (in.progress) in.progress(double(pass) / kPasses);
    runOdometry(in, w, &s);
    M model(rays, s.base.track, in.nominal.t_BL_m,
            {{&s.moved[0], s.step[0]}, {&s.moved[1], s.step[1]}, {&s.moved[2], s.step[2]}});
    std::vector<bool> try_free = free;
    r = solveObservable(rays, model, x, in, &try_free);
    if (!r.ok) {
      RigCalibration failed;
      failed.rms_before = failed.rms_after = 0.0;
      failed.warnings.push_back("nothing calibrated: " + r.reason);
      return failed;
    }
    if (pass == 0) rms_before = r.residual_before_m;
    free = try_free;
    x = r.x;
    w.radius_left_m += x(kRadiusLeft);
    w.radius_right_m += x(kRadiusRight);
    w.wheel_distance_m += x(kTrack);
    x(kRadiusLeft) = x(kRadiusRight) = x(kTrack) = 0.0;  // now in w
  }
  const MobileOdometryRun final_run = in.odometry(w);
  if (in.progress) in.progress(1.0);
  return report(in, x, w, r, free, final_run, rms_before);
}

}  // namespace sweepmap
