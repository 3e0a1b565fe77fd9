#include "calib/axis_offset.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "calib/parameter_information.hpp"
#include "core/angles.hpp"

namespace sweepmap {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
// A scaled singular value of the rig's reduced Jacobian below this: a direction the planes do
// not constrain at all (the encoder zero's is ~1e-13; the weakest determined one on the default
// plates ~1e-2).
constexpr double kUnobservable = 1e-7;

// Raw moments of points (relative to a reference) for the plane fit of Eq. 13.
struct Moments {
  double n = 0, x = 0, y = 0, z = 0, xx = 0, xy = 0, yy = 0, xz = 0, yz = 0, zz = 0;
  void add(double px, double py, double pz) {
    n += 1;
    x += px;
    y += py;
    z += pz;
    xx += px * px;
    xy += px * py;
    yy += py * py;
    xz += px * pz;
    yz += py * pz;
    zz += pz * pz;
  }
  // The least-squares plane z = a x + b y + c (Eq. 13, solved on centred moments) and the
  // RMS of its point-to-plane distances (Eq. 14). False if the points do not fix a, b.
  bool fit(PlaneFitEq13* plane, double* rmse) const {
    const double sxx = xx - x * x / n, sxy = xy - x * y / n, syy = yy - y * y / n;
    const double sxz = xz - x * z / n, syz = yz - y * z / n, szz = zz - z * z / n;
    const double det = sxx * syy - sxy * sxy;
    if (n < 3 || !(std::fabs(det) > 1e-12 * (sxx * syy + 1e-300))) return false;
    const double a = (syy * sxz - sxy * syz) / det;
    const double b = (sxx * syz - sxy * sxz) / det;
    plane->a = a;
    plane->b = b;
    plane->c = (z - a * x - b * y) / n;
    const double rss = std::max(0.0, szz - a * sxz - b * syz);
    *rmse = std::sqrt(rss / (n * (1 + a * a + b * b)));
    return true;
  }
};

// Eq. 7 (the paper's model: no tilt, no encoder zero) on a precomputed sample.
template <class Pre>
Eigen::Vector3d eq7(const Pre& p, double m, double n) {
  // x = M cos a - (N + y) sin a,  y = -M sin a - (N + y) cos a
  return {m * p.c - n * p.s - p.ys, -m * p.s - n * p.c - p.yc, p.z};
}

}  // namespace

PlanePoints subsample(const PlanePoints& plane, int max_samples) {
  if (max_samples <= 0 || plane.samples.size() <= static_cast<size_t>(max_samples)) return plane;
  PlanePoints out;
  out.source = plane.source;
  const size_t stride = (plane.samples.size() + max_samples - 1) / max_samples;
  for (size_t i = 0; i < plane.samples.size(); i += stride) out.samples.push_back(plane.samples[i]);
  return out;
}

PlaneFitEq13 fitPlaneEq13(const std::vector<Eigen::Vector3d>& points) {
  // phi = (D^T D)^-1 D^T delta, D = [x y 1], delta = z
  Eigen::MatrixXd d(points.size(), 3);
  Eigen::VectorXd delta(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    d.row(static_cast<Eigen::Index>(i)) << points[i].x(), points[i].y(), 1.0;
    delta(static_cast<Eigen::Index>(i)) = points[i].z();
  }
  const Eigen::Matrix3d dtd = d.transpose() * d;
  Eigen::FullPivLU<Eigen::Matrix3d> lu(dtd);
  if (points.size() < 3 || lu.rank() < 3) {
    throw std::invalid_argument("fitPlaneEq13: the points do not determine z = Ax + By + C");
  }
  const Eigen::Vector3d phi = lu.solve(d.transpose() * delta);
  return {phi(0), phi(1), phi(2)};
}

double planeRmseEq14(const std::vector<Eigen::Vector3d>& points, const PlaneFitEq13& p) {
  double sum = 0.0;
  const double norm2 = p.a * p.a + p.b * p.b + 1.0;
  for (const auto& q : points) {
    const double r = p.a * q.x() + p.b * q.y() - q.z() + p.c;
    sum += r * r / norm2;
  }
  return points.empty() ? 0.0 : std::sqrt(sum / points.size());
}

PlaneRmseObjective::PlaneRmseObjective(const std::vector<PlanePoints>& planes) {
  for (const PlanePoints& plane : planes) {
    std::vector<Pre> pre;
    pre.reserve(plane.samples.size());
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const ProfileSample& s : plane.samples) {
      const double c = std::cos(s.encoder_rad), sn = std::sin(s.encoder_rad);
      pre.push_back({c, sn, s.y_mm * c, s.y_mm * sn, s.z_mm});
      mean += eq7(pre.back(), 0.0, 0.0);
    }
    // A reference near the points keeps the moments small (no cancellation in the fit).
    reference_.push_back(pre.empty() ? mean : Eigen::Vector3d(mean / pre.size()));
    planes_.push_back(std::move(pre));
  }
}

size_t PlaneRmseObjective::samples() const {
  size_t n = 0;
  for (const auto& p : planes_) n += p.size();
  return n;
}

double PlaneRmseObjective::meanRmse(double m_mm, double n_mm) const {
  double sum = 0.0;
  for (size_t k = 0; k < planes_.size(); ++k) {
    Moments mo;
    const Eigen::Vector3d& ref = reference_[k];
    for (const Pre& p : planes_[k]) {
      const Eigen::Vector3d q = eq7(p, m_mm, n_mm);
      mo.add(q.x() - ref.x(), q.y() - ref.y(), q.z() - ref.z());
    }
    PlaneFitEq13 plane;
    double rmse = 0.0;
    if (!mo.fit(&plane, &rmse)) return std::numeric_limits<double>::infinity();
    sum += rmse;
  }
  return planes_.empty() ? 0.0 : sum / planes_.size();
}

GridSearchResult gridSearchAxisOffset(const std::vector<PlanePoints>& planes,
                                      const GridSearchOptions& o) {
  if (!(o.step_mm > 0) || !(o.m_max_mm >= o.m_min_mm) || !(o.n_max_mm >= o.n_min_mm)) {
    throw std::invalid_argument("grid search: needs min <= max and a step > 0");
  }
  const auto t0 = Clock::now();
  const PlaneRmseObjective objective(planes);
  GridSearchResult r;
  // Nodes by index (no accumulated rounding), both ends included.
  const auto nodes = [&](double lo, double hi) {
    std::vector<double> v;
    const auto count = static_cast<long>(std::floor((hi - lo) / o.step_mm + 1e-9)) + 1;
    for (long i = 0; i < count; ++i) v.push_back(lo + i * o.step_mm);
    return v;
  };
  r.m_values = nodes(o.m_min_mm, o.m_max_mm);
  r.n_values = nodes(o.n_min_mm, o.n_max_mm);
  r.s_min_mm = std::numeric_limits<double>::infinity();
  r.s_mm.reserve(r.m_values.size() * r.n_values.size());
  for (const double m : r.m_values) {
    for (const double n : r.n_values) {
      const double s = objective.meanRmse(m, n);
      r.s_mm.push_back(s);
      if (s < r.s_min_mm) {  // Algorithm 1, steps 7-8
        r.s_min_mm = s;
        r.m_mm = m;
        r.n_mm = n;
      }
    }
  }
  r.seconds = secondsSince(t0);
  return r;
}

namespace {

// The points one profile saw on one plane (they share the turntable's angle): residual
// n . p_i(M, N, tilt, zero) - d [mm] each, p_i by the generalised Eq. 7, with analytic
// Jacobians (a profile per residual block keeps Ceres' per-block cost small).
// Residuals: one per point. Parameters: {M, N} 2, tilt 1, encoder zero 1, unit normal 3,
// distance 1.
class ProfileOnPlaneCost : public ceres::CostFunction {
 public:
  ProfileOnPlaneCost(const ProfileSample* first, size_t count)
      : encoder_rad_(first->encoder_rad), samples_(first, first + count) {
    set_num_residuals(static_cast<int>(count));
    *mutable_parameter_block_sizes() = {2, 1, 1, 3, 1};
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double m = parameters[0][0], n_off = parameters[0][1];
    const double tilt = parameters[1][0], zero = parameters[2][0];
    const double* nv = parameters[3];
    const double d = parameters[4][0];
    const double alpha = encoder_rad_ + zero;
    const double c = std::cos(alpha), s = std::sin(alpha);
    const double ct = std::cos(tilt), st = std::sin(tilt);
    // n . Rz(-alpha) v = a v_x + b v_y + n_z v_z
    const double a = nv[0] * c - nv[1] * s, b = nv[0] * s + nv[1] * c;
    for (size_t i = 0; i < samples_.size(); ++i) {
      const ProfileSample& q = samples_[i];
      const double x0 = m - q.z_mm * st, y0 = -(n_off + q.y_mm), z0 = q.z_mm * ct;
      const double px = c * x0 + s * y0, py = -s * x0 + c * y0;
      residuals[i] = nv[0] * px + nv[1] * py + nv[2] * z0 - d;
      if (!jacobians) continue;
      if (jacobians[0]) {
        jacobians[0][2 * i] = a;
        jacobians[0][2 * i + 1] = -b;
      }
      if (jacobians[1]) jacobians[1][i] = -a * q.z_mm * ct - nv[2] * q.z_mm * st;
      if (jacobians[2]) jacobians[2][i] = nv[0] * py - nv[1] * px;
      if (jacobians[3]) {
        jacobians[3][3 * i] = px;
        jacobians[3][3 * i + 1] = py;
        jacobians[3][3 * i + 2] = z0;
      }
      if (jacobians[4]) jacobians[4][i] = -1.0;
    }
    return true;
  }

 private:
  double encoder_rad_;
  std::vector<ProfileSample> samples_;
};

// The best plane through the points placed with `g` (PCA), normal pointing up.
FittedPlane planeThrough(const PlanePoints& plane, const ProfileGeometry& g) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(plane.samples.size());
  for (const auto& s : plane.samples) {
    pts.push_back(profilePointInRigFrame(g, s.y_mm, s.z_mm, s.encoder_rad));
    mean += pts.back();
  }
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d n = eig.eigenvectors().col(0);
  if (n.z() < 0) n = -n;
  FittedPlane f{n, n.dot(mean), std::sqrt(std::max(0.0, eig.eigenvalues()(0)) / pts.size())};
  return f;
}

}  // namespace

std::vector<size_t> findReferencePlanes(const std::vector<PlanePoints>& planes,
                                        const ProfileGeometry& geometry, double azimuth_rad,
                                        double tilt_rad, double tolerance_rad) {
  const Eigen::Vector3d declared(std::sin(tilt_rad) * std::cos(azimuth_rad),
                                 std::sin(tilt_rad) * std::sin(azimuth_rad), std::cos(tilt_rad));
  std::vector<size_t> found;
  for (size_t k = 0; k < planes.size(); ++k) {
    if (planes[k].samples.size() < 3) continue;
    const Eigen::Vector3d n = planeThrough(planes[k], geometry).normal;
    if (std::acos(std::clamp(n.dot(declared), -1.0, 1.0)) <= tolerance_rad) found.push_back(k);
  }
  return found;
}

namespace {

// A unit normal held in the vertical plane of a known azimuth (the base's reference face): it
// turns only about the horizontal axis perpendicular to that plane. Ambient 3, tangent 1.
class AzimuthNormalManifold : public ceres::Manifold {
 public:
  explicit AzimuthNormalManifold(double azimuth_rad)
      : axis_(-std::sin(azimuth_rad), std::cos(azimuth_rad), 0.0) {}
  int AmbientSize() const override { return 3; }
  int TangentSize() const override { return 1; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    const Eigen::Map<const Eigen::Vector3d> v(x);
    Eigen::Map<Eigen::Vector3d> out(x_plus_delta);
    out = v * std::cos(delta[0]) + axis_.cross(v) * std::sin(delta[0]);
    return true;
  }
  bool PlusJacobian(const double* x, double* jacobian) const override {
    Eigen::Map<Eigen::Vector3d> j(jacobian);
    j = axis_.cross(Eigen::Vector3d(x[0], x[1], x[2]));
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    const Eigen::Map<const Eigen::Vector3d> a(x), b(y);
    y_minus_x[0] = std::atan2(a.cross(b).dot(axis_), a.dot(b));
    return true;
  }
  bool MinusJacobian(const double* x, double* jacobian) const override {
    Eigen::Map<Eigen::Vector3d> j(jacobian);
    j = axis_.cross(Eigen::Vector3d(x[0], x[1], x[2]));
    return true;
  }
  // n with its component along the axis removed: the nearest normal of that azimuth.
  Eigen::Vector3d project(const Eigen::Vector3d& n) const {
    return (n - n.dot(axis_) * axis_).normalized();
  }

 private:
  Eigen::Vector3d axis_;
};

// The encoder zero that turns the reference planes' normals (placed with the initial
// geometry) to the declared azimuth on average: the solver's start. A larger zero turns the
// cloud clockwise, so the azimuth seen drops by the zero's excess.
double zeroFromReference(const std::vector<PlanePoints>& planes, const AxisOffsetOptions& o) {
  double sum = 0.0;
  for (const size_t k : o.reference_planes) {
    const Eigen::Vector3d n = planeThrough(planes.at(k), o.initial).normal;
    sum += std::remainder(std::atan2(n.y(), n.x()) - o.reference_azimuth_rad, 2 * M_PI);
  }
  return o.initial.encoder_zero_rad + sum / static_cast<double>(o.reference_planes.size());
}

bool isReference(const AxisOffsetOptions& o, size_t plane) {
  return std::find(o.reference_planes.begin(), o.reference_planes.end(), plane) !=
         o.reference_planes.end();
}

// The problem's state: the rig's parameters and one (normal, distance) per plane.
struct Problem {
  double mn[2], tilt, zero;
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> distances;
  std::unique_ptr<ceres::Problem> problem;
  size_t residuals = 0;
};

// The reference planes' normals are held to their azimuth only while the zero is estimated
// (with the zero held, the azimuth they show is the nominal zero's, not the face's).
void buildProblem(const std::vector<PlanePoints>& planes, const AxisOffsetOptions& o,
                  bool estimate_tilt, bool estimate_zero, Problem* p) {
  ProfileGeometry g = o.initial;
  if (estimate_zero && !o.reference_planes.empty())
    g.encoder_zero_rad = zeroFromReference(planes, o);
  p->mn[0] = g.m_mm;
  p->mn[1] = g.n_mm;
  p->tilt = g.laser_tilt_rad;
  p->zero = g.encoder_zero_rad;
  p->normals.clear();
  p->distances.clear();
  for (const auto& plane : planes) {
    const FittedPlane f = planeThrough(plane, g);
    p->normals.push_back(f.normal);
    p->distances.push_back(f.distance_mm);
  }
  p->problem = std::make_unique<ceres::Problem>();
  p->residuals = 0;
  for (size_t k = 0; k < planes.size(); ++k) {
    const std::vector<ProfileSample>& samples = planes[k].samples;
    // One block per run of samples from one profile (one turntable angle).
    for (size_t i = 0, j = 0; i < samples.size(); i = j) {
      for (j = i + 1; j < samples.size() && samples[j].encoder_rad == samples[i].encoder_rad;) ++j;
      p->problem->AddResidualBlock(new ProfileOnPlaneCost(&samples[i], j - i), nullptr, p->mn,
                                   &p->tilt, &p->zero, p->normals[k].data(), &p->distances[k]);
      p->residuals += j - i;
    }
    if (estimate_zero && isReference(o, k)) {
      auto* manifold = new AzimuthNormalManifold(o.reference_azimuth_rad);
      p->normals[k] = manifold->project(p->normals[k]);
      p->problem->SetManifold(p->normals[k].data(), manifold);
    } else {
      p->problem->SetManifold(p->normals[k].data(), new ceres::SphereManifold<3>());
    }
  }
  if (!estimate_tilt) p->problem->SetParameterBlockConstant(&p->tilt);
  if (!estimate_zero) p->problem->SetParameterBlockConstant(&p->zero);
}

double rmsOf(Problem* p) {
  double cost = 0.0;
  p->problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  return std::sqrt(2.0 * cost / std::max<size_t>(1, p->residuals));
}

// How well the planes determine the rig's estimated parameters (names[i]): their information
// with the planes eliminated (calib/parameter_information.hpp, in a fixed order), scaled by
// their Jacobian columns' norms; a singular value near 0 is a direction of the rig's
// parameters that no plane constrains.
struct Observability {
  std::vector<std::string> names;
  Eigen::VectorXd singular_values;  // ascending
  Eigen::MatrixXd directions;       // columns: the matching right singular vectors
  // J^T J of the rig's parameters (in `names`' order) with the planes eliminated; its inverse
  // is their covariance per unit residual variance.
  Eigen::MatrixXd information;
};

Observability analyse(Problem* p, const std::vector<double*>& rig_blocks,
                      const std::vector<std::string>& rig_names) {
  std::vector<double*> planes;
  for (size_t k = 0; k < p->normals.size(); ++k) {
    planes.push_back(p->normals[k].data());
    planes.push_back(&p->distances[k]);
  }
  const ParameterInformation info = eliminatedInformation(p->problem.get(), planes, rig_blocks);
  const auto k = static_cast<Eigen::Index>(rig_names.size());
  if (!info.ok) {
    return {rig_names, Eigen::VectorXd::Zero(k), Eigen::MatrixXd::Identity(k, k),
            Eigen::MatrixXd::Zero(k, k)};
  }
  // The scaled information is R22^T R22 of the scaled Jacobian: its eigenvalues are the
  // squares of R22's singular values (ascending), its eigenvectors their directions.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaledInformation(info));
  return {rig_names, eig.eigenvalues().cwiseMax(0.0).cwiseSqrt(), eig.eigenvectors(),
          info.information};
}

// Solves with the optional parameters asked for; one the planes cannot determine is held at
// its initial value (with a warning) and the problem solved again without it. Returns the
// observability of the final solution's parameters.
Observability solveHoldingUnobservable(const std::vector<PlanePoints>& planes,
                                       const AxisOffsetOptions& o, Problem* p,
                                       AxisOffsetResult* r) {
  bool estimate_tilt = o.estimate_tilt, estimate_zero = o.estimate_encoder_zero;
  Observability obs;
  for (int attempt = 0; attempt < 3; ++attempt) {  // at most two parameters to drop
    buildProblem(planes, o, estimate_tilt, estimate_zero, p);
    if (attempt == 0) r->rms_before_mm = rmsOf(p);
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;  // 4 + 4m parameters
    so.max_num_iterations = o.max_iterations;
    so.function_tolerance = 1e-12;
    so.parameter_tolerance = 1e-12;
    so.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(so, p->problem.get(), &summary);
    r->iterations = static_cast<int>(summary.iterations.size());
    r->converged = summary.termination_type == ceres::CONVERGENCE;
    std::vector<double*> blocks = {p->mn};
    std::vector<std::string> names = {"M", "N"};
    if (estimate_tilt) blocks.push_back(&p->tilt), names.push_back("laser_tilt");
    if (estimate_zero) blocks.push_back(&p->zero), names.push_back("encoder_zero");
    obs = analyse(p, blocks, names);
    bool dropped = false;
    for (Eigen::Index e = 0; e < obs.singular_values.size(); ++e) {
      if (obs.singular_values(e) > kUnobservable) continue;
      for (size_t i = 2; i < names.size(); ++i) {
        if (std::fabs(obs.directions(static_cast<Eigen::Index>(i), e)) < 0.3) continue;
        r->warnings.push_back(
            names[i] +
            " is not observable from these planes (a direction of the parameters they do not "
            "constrain); held at its initial value" +
            (names[i] == "encoder_zero" ? std::string(": only a sweep over the base's reference "
                                                      "face, whose azimuth is known, fixes it")
                                        : std::string()));
        (names[i] == "laser_tilt" ? estimate_tilt : estimate_zero) = false;
        dropped = true;
      }
    }
    if (!dropped) break;
  }
  r->tilt_estimated = estimate_tilt;
  r->zero_estimated = estimate_zero;
  return obs;
}

// A direction left unconstrained after the optional parameters were dropped involves M or N.
void flagUnobservable(const Observability& obs, AxisOffsetResult* r) {
  r->smallest_singular_value = obs.singular_values.size() ? obs.singular_values(0) : 0.0;
  for (Eigen::Index e = 0; e < obs.singular_values.size(); ++e) {
    if (obs.singular_values(e) > kUnobservable) continue;
    std::ostringstream w;
    w << "M and N are not observable from these planes (a direction of the parameters with "
         "scaled singular value "
      << obs.singular_values(e) << "): give non-parallel, tilted plate poses";
    r->warnings.push_back(w.str());
    r->observable = false;
  }
}

// r->covariance and the sigmas: rows M, N [mm], tilt, zero [deg].
void fillCovariance(const Observability& obs, double variance, double reference_sigma_rad,
                    AxisOffsetResult* r) {
  const Eigen::MatrixXd unit = covarianceFromInformation(obs.information);
  if (!unit.allFinite()) {
    r->warnings.push_back("the covariance is singular: no standard deviations");
    return;
  }
  // Rows of r->covariance: M, N, laser tilt [deg], encoder zero [deg].
  const auto row = [](const std::string& name) {
    return name == "M" ? 0 : name == "N" ? 1 : name == "laser_tilt" ? 2 : 3;
  };
  const auto scale = [](const std::string& name) { return name.size() > 1 ? kRadToDeg : 1.0; };
  for (size_t a = 0; a < obs.names.size(); ++a) {
    for (size_t b = 0; b < obs.names.size(); ++b) {
      r->covariance(row(obs.names[a]), row(obs.names[b])) = unit(Eigen::Index(a), Eigen::Index(b)) *
                                                            variance * scale(obs.names[a]) *
                                                            scale(obs.names[b]);
    }
  }
  if (r->zero_estimated) {
    r->sigma_zero_fit_deg = std::sqrt(r->covariance(3, 3));
    // The face's construction error moves the zero one for one and nothing else.
    const double ref_deg = reference_sigma_rad * kRadToDeg;
    r->covariance(3, 3) += ref_deg * ref_deg;
  }
  const Eigen::Vector4d v = r->covariance.diagonal();
  r->sigma_m_mm = std::sqrt(v(0));
  r->sigma_n_mm = std::sqrt(v(1));
  if (r->tilt_estimated) r->sigma_tilt_deg = std::sqrt(v(2));
  if (r->zero_estimated) r->sigma_zero_deg = std::sqrt(v(3));
}

// Standard deviations: the inverse of J^T J of the estimated parameters with the planes
// eliminated (analyse(), calib/parameter_information.hpp), scaled by the residuals' variance;
// NaN (with a warning) where it is singular.
void standardDeviations(size_t plane_count, const Problem& p, const Observability& obs,
                        double reference_sigma_rad, AxisOffsetResult* r) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r->sigma_m_mm = r->sigma_n_mm = r->sigma_tilt_deg = r->sigma_zero_deg = nan;
  if (!r->observable) return;
  const double dof = static_cast<double>(p.residuals) -
                     (2 + r->tilt_estimated + r->zero_estimated) - 3.0 * plane_count;
  const double variance = r->rms_after_mm * r->rms_after_mm * p.residuals / std::max(1.0, dof);
  fillCovariance(obs, variance, reference_sigma_rad, r);
}

// Warnings for parameters whose standard deviation exceeds the options' limits; M or N that
// does is not determined.
void flagWeak(const AxisOffsetOptions& o, AxisOffsetResult* r) {
  const auto weak = [&](const char* name, double sigma, double limit, const char* unit) {
    if (!(sigma > limit)) return;
    std::ostringstream w;
    w << name << " is poorly determined by these planes: sigma " << sigma << " " << unit << " > "
      << limit << " " << unit;
    r->warnings.push_back(w.str());
  };
  weak("M", r->sigma_m_mm, o.max_sigma_mm, "mm");
  weak("N", r->sigma_n_mm, o.max_sigma_mm, "mm");
  if (r->sigma_m_mm > o.max_sigma_mm || r->sigma_n_mm > o.max_sigma_mm) r->observable = false;
  weak("laser_tilt", r->sigma_tilt_deg, o.max_sigma_deg, "deg");
  weak("encoder_zero", r->sigma_zero_deg, o.max_sigma_deg, "deg");
}

// The fitted planes with their points' RMS, and the paper's rule: they must not be parallel.
void reportPlanes(const std::vector<PlanePoints>& planes, const Problem& p,
                  const AxisOffsetOptions& o, AxisOffsetResult* r) {
  for (size_t k = 0; k < planes.size(); ++k) {
    double sum = 0.0;
    for (const auto& s : planes[k].samples) {
      const double d =
          p.normals[k].dot(profilePointInRigFrame(r->geometry, s.y_mm, s.z_mm, s.encoder_rad)) -
          p.distances[k];
      sum += d * d;
    }
    r->planes.push_back({p.normals[k], p.distances[k], std::sqrt(sum / planes[k].samples.size())});
  }
  for (size_t a = 0; a < r->planes.size(); ++a) {
    for (size_t b = a + 1; b < r->planes.size(); ++b) {
      const double c = std::fabs(r->planes[a].normal.dot(r->planes[b].normal));
      r->largest_plane_angle_deg =
          std::max(r->largest_plane_angle_deg, std::acos(std::min(1.0, c)) * kRadToDeg);
    }
  }
  if (r->largest_plane_angle_deg < o.min_plane_angle_deg) {
    std::ostringstream w;
    w << "the planes are parallel (largest angle between their normals "
      << r->largest_plane_angle_deg << " deg < " << o.min_plane_angle_deg
      << " deg): M and N are not determined; Zhao 2021 needs non-parallel plate poses";
    r->warnings.push_back(w.str());
    r->observable = false;
  }
}

}  // namespace

AxisOffsetResult solveAxisOffset(const std::vector<PlanePoints>& planes,
                                 const AxisOffsetOptions& o) {
  if (planes.empty()) throw std::invalid_argument("axis offset: no plane given");
  for (const auto& plane : planes) {
    if (plane.samples.size() < 3) {
      throw std::invalid_argument("axis offset: " + plane.source + " has fewer than 3 points");
    }
  }
  const auto t0 = Clock::now();
  AxisOffsetResult r;
  Problem p;
  const Observability obs = solveHoldingUnobservable(planes, o, &p, &r);
  flagUnobservable(obs, &r);
  r.geometry = {p.mn[0], p.mn[1], p.tilt, p.zero};
  r.rms_after_mm = rmsOf(&p);
  r.residuals = p.residuals;
  standardDeviations(planes.size(), p, obs, o.reference_azimuth_sigma_rad, &r);
  flagWeak(o, &r);
  reportPlanes(planes, p, o, &r);
  r.seconds = secondsSince(t0);
  return r;
}

}  // namespace sweepmap
