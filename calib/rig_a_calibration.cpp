#include "calib/rig_a_calibration.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "calib/parameter_information.hpp"
#include "calib/rotating_geometry.hpp"
#include "core/angles.hpp"

namespace sweepmap {
namespace {

constexpr double kCauchy = 2.3849;  // 95 % efficiency, in sigmas
constexpr int kParams = 4;          // alpha, x, tilt, mirror

// A ray in the form the residuals need: cos, sin of phi, range [mm], theta.
struct PreRay {
  double c, s, r_mm, theta;
};

PreRay pre(const SweepRay& r) {
  return {std::cos(r.phi_rad), std::sin(r.phi_rad), 1e3 * r.range_m, r.theta_rad};
}

// A ray's origin [mm] and unit direction in O' with g = (x [mm], tilt [rad], mirror [rad])
// (header's model): p_O' = origin + r direction.
template <class T>
void rayInOPrime(const PreRay& ray, const T* g, T* origin, T* dir) {
  using std::cos;
  using std::sin;
  const T th = T(ray.theta) + g[2];
  const T cth = cos(th);
  const T dx = sin(g[1]) * cth;
  const T dy = sin(th);
  origin[0] = ray.c * g[0];
  origin[1] = ray.s * g[0];
  origin[2] = T(0.0);
  dir[0] = ray.c * dx - ray.s * dy;
  dir[1] = ray.s * dx + ray.c * dy;
  dir[2] = cos(g[1]) * cth;
}

// p_O' [mm] of a ray with g.
template <class T>
void placeInOPrime(const PreRay& ray, const T* g, T* p) {
  T o[3], d[3];
  rayInOPrime(ray, g, o, d);
  for (int i = 0; i < 3; ++i) p[i] = o[i] + ray.r_mm * d[i];
}

// Rays more glancing than this to their plane (|cos incidence|) stay out of the solve: the
// range a plane predicts for them is ill-conditioned.
constexpr double kMinCosIncidence = 0.05;

// The residual of a ray against the plane n . p = dist (n unit, both in the frame of the
// ray's origin and direction): its distance to the plane, written as w (r - r_plane), r_plane
// = (dist - n . origin) / (n . dir) the range at which the ray meets the plane and w the ray's
// n . dir when the problem was built (held fixed). Its value is the point-to-plane distance;
// its derivatives are those of the plane's point on the ray, free of the measured range. The
// point-to-plane distance n . (origin + r dir) - dist differentiates into r (n . d dir): the
// range's noise in the Jacobian, correlated with the residual's own noise (errors in
// variables, a bias of order sigma^2 / r^2). On the plan's logs the change was small (offset
// -0.04 mm, mirror -0.0003 deg); the mirror's lean was the depth edges' (calib rig's
// segmentation, depth_edge_rays).
template <class T>
T rayPlaneResidual(const PreRay& ray, double w, const T* origin, const T* dir, const T* n,
                   const T& dist) {
  const T a = n[0] * origin[0] + n[1] * origin[1] + n[2] * origin[2];
  const T b = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2];
  return w * (ray.r_mm - (dist - a) / b);
}

// A room wall's unit normal (cos a cos lean, sin a cos lean, sin lean) in O turned into the
// sweep's O' (by -phi_s).
template <class T>
void wallNormalInOPrime(double ca, double sa, const T& phi, const T* wall, T* n) {
  using std::cos;
  using std::sin;
  const T cl = cos(wall[0]);
  const T nx = ca * cl, ny = sa * cl;
  const T cp = cos(phi), sp = sin(phi);
  n[0] = cp * nx + sp * ny;
  n[1] = -sp * nx + cp * ny;
  n[2] = sin(wall[0]);
}

// A ray of a room wall: parameters g (3), phi_s (1), wall (lean [rad], distance [mm]).
struct WallRayCost {
  PreRay ray;
  double ca, sa, w, inv_sigma;
  template <class T>
  bool operator()(const T* g, const T* phi, const T* wall, T* e) const {
    T o[3], d[3], n[3];
    rayInOPrime(ray, g, o, d);
    wallNormalInOPrime(ca, sa, phi[0], wall, n);
    e[0] = rayPlaneResidual(ray, w, o, d, n, wall[1]) * inv_sigma;
    return true;
  }
  static ceres::CostFunction* Create(const PreRay& r, double a, double w, double inv_sigma) {
    return new ceres::AutoDiffCostFunction<WallRayCost, 1, 3, 1, 2>(
        new WallRayCost{r, std::cos(a), std::sin(a), w, inv_sigma});
  }
};

// A ray of any other plane, in O': parameters g (3), unit normal (3), distance [mm] (1).
struct PlaneRayCost {
  PreRay ray;
  double w, inv_sigma;
  template <class T>
  bool operator()(const T* g, const T* n, const T* dist, T* e) const {
    T o[3], d[3];
    rayInOPrime(ray, g, o, d);
    e[0] = rayPlaneResidual(ray, w, o, d, n, dist[0]) * inv_sigma;
    return true;
  }
  static ceres::CostFunction* Create(const PreRay& r, double w, double inv_sigma) {
    return new ceres::AutoDiffCostFunction<PlaneRayCost, 1, 3, 3, 1>(
        new PlaneRayCost{r, w, inv_sigma});
  }
};

// The plate's rays placed with g, in metres (calib/plate_model.hpp's frame O').
std::vector<PlateRay> placePlateRays(const std::vector<SweepRay>& rays, const double* g) {
  const Eigen::Matrix3d R_L = rotating::lidarRotation(g[1], g[2]);
  std::vector<PlateRay> out;
  out.reserve(rays.size());
  for (const SweepRay& r : rays) {
    const Eigen::Matrix3d Rz = rotating::rotZ(r.phi_rad);
    out.push_back({Rz * Eigen::Vector3d(1e-3 * g[0], 0, 0),
                   Rz * R_L * rotating::pointInLidar(1.0, r.theta_rad), r.range_m});
  }
  return out;
}

// The plate of one sweep: parameters alpha (1), phi_s (1). Its angle in O' (`beta`) is the
// agreeing estimator's (calib/plate_model.hpp fitPlateAgreeing) with the rays placed with g as
// the walls determined it, the offset shifted to where the plate's two views agree (a snapshot,
// refreshed with each new g, placePlates): the plates do not move g (their views cannot tell
// the offset from the plate's height); g's uncertainty reaches alpha by propagation. The
// estimator is a step function of the geometry, so the plate is a fixed angle here.
struct PlateCost {
  const double* beta;
  double inv_sigma;
  template <class T>
  bool operator()(const T* alpha, const T* phi, T* e) const {
    e[0] = (T(*beta) - (alpha[0] - phi[0])) * inv_sigma;
    return true;
  }
};

// The state of the problem: the four parameters (g, alpha) and per sweep its attitude and
// planes.
struct SweepState {
  double phi = 0.0;
  bool plate = false;
  std::vector<double> plate_hits;  // the measured hits' weights (plateHitWeights)
  double beta = 0.0;               // the plate's angle in O' (PlateCost)
  std::vector<int> wall_class;     // per plane: 0..3 a room wall (azimuth class * 90 deg), -1 free
  std::vector<double> azimuth;     // per room wall [rad]
  std::vector<std::array<double, 2>> wall;  // lean, distance
  std::vector<Eigen::Vector3d> normal;      // free planes
  std::vector<double> distance;
  std::vector<std::vector<char>> keep;  // per plane per ray: not clutter
  std::vector<std::vector<PreRay>> rays;
};

struct State {
  double g[3];
  double g_plate[3];  // g as the plates see it (the walls' last solution, plate_shift_mm on x)
  double plate_shift_mm = 0.0;    // where the plate's two views agree, from the walls' x
  double views_per_offset = 0.0;  // d (view 0 - view 1) / d x [rad/mm], once known
  double alpha;
  std::vector<SweepState> sweeps;
  double sigma_mm = 10.0;
  double sigma_plate_rad = 3.5e-4;  // 0.02 deg until the plates' scatter is known
  bool plate_robust = false;        // Cauchy on the plates once their scatter is known
  bool held[kParams] = {false, false, false, false};  // alpha, x, tilt, mirror
};

// The least-squares plane through points: unit normal and distance (n . p = d).
void fitPlane(const std::vector<Eigen::Vector3d>& pts, Eigen::Vector3d* n, double* d) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= double(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  *n = eig.eigenvectors().col(0);
  if (n->dot(mean) > 0) *n = -*n;  // toward the sensor
  *d = n->dot(mean);
}

std::vector<Eigen::Vector3d> placed(const std::vector<PreRay>& rays, const double* g) {
  std::vector<Eigen::Vector3d> pts(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) placeInOPrime(rays[i], g, pts[i].data());
  return pts;
}

// The sweep's attitude from the plate model, its planes fitted and the room walls picked
// (the largest vertical plane of each azimuth class), its attitude refined from them.
SweepState initSweep(const RigASweep& s, const RigASolveOptions& o, const State& st) {
  SweepState ss;
  const auto pr = placePlateRays(s.plate_rays, st.g);
  const PlateModelFit fit = fitPlateModel(o.plate, pr, o.min_plate_hits);
  ss.plate = fit.found;
  if (fit.found) {
    ss.phi = st.alpha - fit.angle_rad;
    ss.beta = fit.angle_rad;
    ss.plate_hits = plateHitWeights(o.plate, pr, s.plate_beams);
  }
  const size_t n = s.planes.size();
  ss.wall_class.assign(n, -1);
  ss.azimuth.assign(n, 0.0);
  ss.wall.assign(n, {0.0, 0.0});
  ss.normal.assign(n, Eigen::Vector3d::UnitZ());
  ss.distance.assign(n, 0.0);
  std::map<int, size_t> largest;  // class -> plane
  const double tol = o.wall_azimuth_tolerance_deg * kDegToRad;
  ss.rays.resize(n);
  for (size_t k = 0; k < n; ++k) {
    for (const auto& r : s.planes[k].rays) ss.rays[k].push_back(pre(r));
    ss.keep.push_back(std::vector<char>(ss.rays[k].size(), 1));
    fitPlane(placed(ss.rays[k], st.g), &ss.normal[k], &ss.distance[k]);
    const Eigen::Vector3d n_O = rotating::rotZ(ss.phi) * ss.normal[k];
    if (std::fabs(n_O.z()) > o.wall_max_normal_z) continue;
    const double az = std::atan2(n_O.y(), n_O.x());
    const double q = std::round(az / (M_PI / 2));
    if (std::fabs(az - q * M_PI / 2) > tol) continue;
    const int cls = (int(q) % 4 + 4) % 4;
    if (!largest.count(cls) || s.planes[largest[cls]].rays.size() < s.planes[k].rays.size()) {
      largest[cls] = k;
    }
  }
  double shift = 0.0;
  for (const auto& [cls, k] : largest) {
    const Eigen::Vector3d n_O = rotating::rotZ(ss.phi) * ss.normal[k];
    shift += wrapAngle(cls * M_PI / 2 - std::atan2(n_O.y(), n_O.x())) / double(largest.size());
  }
  ss.phi += shift;
  for (const auto& [cls, k] : largest) {
    const Eigen::Vector3d n_O = rotating::rotZ(ss.phi) * ss.normal[k];
    ss.wall_class[k] = cls;
    ss.azimuth[k] = cls * M_PI / 2;
    ss.wall[k] = {std::asin(std::clamp(n_O.z(), -1.0, 1.0)), ss.distance[k]};
  }
  return ss;
}

// Unscaled residual [mm] of ray i of plane k of a sweep at the state.
// Plane k of a sweep at the state, in O': unit normal and distance [mm].
void planeInOPrime(const SweepState& ss, size_t k, Eigen::Vector3d* n, double* dist) {
  if (ss.wall_class[k] >= 0) {
    wallNormalInOPrime(std::cos(ss.azimuth[k]), std::sin(ss.azimuth[k]), ss.phi, ss.wall[k].data(),
                       n->data());
    *dist = ss.wall[k][1];
  } else {
    *n = ss.normal[k];
    *dist = ss.distance[k];
  }
}

// Unscaled residual [mm] of ray i of plane k of a sweep at the state: its point's distance to
// the plane.
double residualMm(const State& st, const SweepState& ss, size_t k, size_t i) {
  Eigen::Vector3d n, p;
  double dist = 0.0;
  planeInOPrime(ss, k, &n, &dist);
  placeInOPrime(ss.rays[k][i], st.g, p.data());
  return n.dot(p) - dist;
}

// The weight of ray i of plane k in the ray-form residual (rayPlaneResidual): n . dir at the
// state.
double rayWeight(const State& st, const SweepState& ss, size_t k, size_t i) {
  Eigen::Vector3d n, o, d;
  double dist = 0.0;
  planeInOPrime(ss, k, &n, &dist);
  rayInOPrime(ss.rays[k][i], st.g, o.data(), d.data());
  return n.dot(d);
}

std::vector<double> keptResiduals(const State& st) {
  std::vector<double> e;
  for (const auto& ss : st.sweeps) {
    for (size_t k = 0; k < ss.rays.size(); ++k) {
      for (size_t i = 0; i < ss.rays[k].size(); ++i) {
        if (ss.keep[k][i]) e.push_back(residualMm(st, ss, k, i));
      }
    }
  }
  return e;
}

double robustSigma(std::vector<double> e) {
  if (e.empty()) return 1.0;
  for (double& v : e) v = std::fabs(v);
  std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
  return std::max(1e-3, 1.4826 * e[e.size() / 2]);
}

// RMS [mm] of the residuals within 3 robust sigmas (what the planes explain; clutter out).
double inlierRms(const std::vector<double>& e, double sigma) {
  double ss = 0.0;
  size_t n = 0;
  for (const double v : e) {
    if (std::fabs(v) > 3.0 * sigma) continue;
    ss += v * v;
    ++n;
  }
  return n ? std::sqrt(ss / double(n)) : 0.0;
}

struct Built {
  std::unique_ptr<ceres::Problem> problem;
  std::unique_ptr<ceres::LossFunction> loss, plate_loss;
  std::vector<PlateCost*> plate_costs;
};

// Every kept ray and every plate into one problem over the state's memory.
Built buildProblem(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o, State* st) {
  Built b;
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.manifold_ownership = ceres::TAKE_OWNERSHIP;
  b.problem = std::make_unique<ceres::Problem>(po);
  b.loss = std::make_unique<ceres::CauchyLoss>(kCauchy);
  b.plate_loss = std::make_unique<ceres::CauchyLoss>(3.0);
  const double inv = 1.0 / st->sigma_mm;
  b.problem->AddParameterBlock(st->g, 3);
  b.problem->AddParameterBlock(&st->alpha, 1);
  for (size_t s = 0; s < st->sweeps.size(); ++s) {
    SweepState& ss = st->sweeps[s];
    for (size_t k = 0; k < ss.rays.size(); ++k) {
      for (size_t i = 0; i < ss.rays[k].size(); ++i) {
        if (!ss.keep[k][i]) continue;
        const double w = rayWeight(*st, ss, k, i);
        if (!(std::fabs(w) >= kMinCosIncidence)) continue;
        if (ss.wall_class[k] >= 0) {
          b.problem->AddResidualBlock(WallRayCost::Create(ss.rays[k][i], ss.azimuth[k], w, inv),
                                      b.loss.get(), st->g, &ss.phi, ss.wall[k].data());
        } else {
          b.problem->AddResidualBlock(PlaneRayCost::Create(ss.rays[k][i], w, inv), b.loss.get(),
                                      st->g, ss.normal[k].data(), &ss.distance[k]);
        }
      }
      if (ss.wall_class[k] < 0 && b.problem->HasParameterBlock(ss.normal[k].data())) {
        b.problem->SetManifold(ss.normal[k].data(), new ceres::SphereManifold<3>());
      }
    }
    if (ss.plate) {
      auto* cost = new PlateCost{&ss.beta, 1.0 / st->sigma_plate_rad};
      b.problem->AddResidualBlock(new ceres::AutoDiffCostFunction<PlateCost, 1, 1, 1>(cost),
                                  st->plate_robust ? b.plate_loss.get() : nullptr, &st->alpha,
                                  &ss.phi);
    }
  }
  std::vector<int> held_g;
  for (int c = 0; c < 3; ++c) {
    if (st->held[c + 1]) held_g.push_back(c);
  }
  if (held_g.size() == 3) {
    b.problem->SetParameterBlockConstant(st->g);
  } else if (!held_g.empty()) {
    b.problem->SetManifold(st->g, new ceres::SubsetManifold(3, held_g));
  }
  if (st->held[0] && b.problem->HasParameterBlock(&st->alpha)) {
    b.problem->SetParameterBlockConstant(&st->alpha);
  }
  return b;
}

bool solve(const RigASolveOptions& o, Built* b) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  // Eigen's sparse Cholesky: SuiteSparse's runs OpenMP threads, whose sums may change from
  // run to run; the same logs must give the same bytes.
  so.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-10;
  so.num_threads = 1;  // the same result whatever the machine
  ceres::Solver::Summary summary;
  ceres::Solve(so, b->problem.get(), &summary);
  return summary.termination_type == ceres::CONVERGENCE;
}

// Each room wall's kept rays by cell of the wall (along it, up), in O.
template <class F>
void forWallCells(const RigASolveOptions& o, const State& st, F&& f) {
  for (size_t s = 0; s < st.sweeps.size(); ++s) {
    const SweepState& ss = st.sweeps[s];
    for (size_t k = 0; k < ss.rays.size(); ++k) {
      if (ss.wall_class[k] < 0) continue;
      const auto pts = placed(ss.rays[k], st.g);
      const double ca = std::cos(ss.azimuth[k] - ss.phi), sa = std::sin(ss.azimuth[k] - ss.phi);
      for (size_t i = 0; i < pts.size(); ++i) {
        if (!ss.keep[k][i]) continue;
        const double u = -sa * pts[i].x() + ca * pts[i].y();  // along the wall
        f(s, k, i, long(std::floor(1e-3 * u / o.clutter_cell_m)),
          long(std::floor(1e-3 * pts[i].z() / o.clutter_cell_m)));
      }
    }
  }
}

double median(std::vector<double> e) {
  std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
  return e[e.size() / 2];
}

// Clutter on the room walls (a whiteboard proud of one): the rays of a sweep's wall cell whose
// median residual is beyond the limit are left out, and so are its neighbours' (8 around, on
// the same wall in the same sweep): clutter has extent, and a cell it covers in part keeps a
// median under the limit while its covered rays, a couple of noise sigmas proud, still pull
// the wall (a 20 mm whiteboard moved the offset by tenths of a millimetre that way).
void removeClutter(const RigASolveOptions& o, State* st) {
  using Cell = std::tuple<size_t, size_t, long, long>;
  std::map<Cell, std::vector<size_t>> cells;
  forWallCells(o, *st, [&](size_t s, size_t k, size_t i, long u, long z) {
    cells[{s, k, u, z}].push_back(i);
  });
  std::set<Cell> clutter;
  for (const auto& [cell, idx] : cells) {
    if (idx.size() < 15) continue;
    const size_t s = std::get<0>(cell), k = std::get<1>(cell);
    std::vector<double> e;
    for (const size_t i : idx) e.push_back(residualMm(*st, st->sweeps[s], k, i));
    if (std::fabs(median(e)) > o.clutter_limit_mm) clutter.insert(cell);
  }
  for (const auto& [cell, idx] : cells) {
    const auto [s, k, u, z] = cell;
    bool near = false;
    for (long du = -1; du <= 1 && !near; ++du) {
      for (long dz = -1; dz <= 1 && !near; ++dz) near = clutter.count({s, k, u + du, z + dz}) > 0;
    }
    if (!near) continue;
    for (const size_t i : idx) st->sweeps[s].keep[k][i] = 0;
  }
}

// The walls' residuals by cell of 0.5 m pooled over the sweeps (same wall, same place in O;
// cells of 100 rays or more): what the walls show beyond the noise.
struct WallCells {
  double median_rms_mm = 0.0;  // RMS of the cells' medians
  // Variance [mm^2] of the cells' medians beyond what the noise gives a median of their rays
  // (pi/2 sigma^2 / rays): structure of the walls the model does not have (clutter left,
  // a bend, another error), shared by the rays of a cell.
  double between_mm2 = 0.0;
  double rays_per_cell = 0.0;  // mean
  // The variance factor of an estimate from rays that share their cell's error (the design
  // effect of clustered samples, 1 + (m - 1) rho, rho the share of the cells' variance in the
  // rays' variance): the rays of a cell count as fewer than they are.
  double design_effect = 1.0;
};

WallCells wallCells(const RigASolveOptions& o, const State& st) {
  std::map<std::tuple<int, long, long>, std::vector<double>> cells;
  forWallCells(o, st, [&](size_t s, size_t k, size_t i, long u, long z) {
    cells[{st.sweeps[s].wall_class[k], u, z}].push_back(residualMm(st, st.sweeps[s], k, i));
  });
  double ss = 0.0, noise = 0.0, rays = 0.0;
  size_t n = 0;
  const double var = st.sigma_mm * st.sigma_mm;
  for (const auto& [cell, e] : cells) {
    if (e.size() < 100) continue;
    const double m = median(e);
    ss += m * m;
    noise += 0.5 * M_PI * var / double(e.size());
    rays += double(e.size());
    ++n;
  }
  WallCells w;
  if (n == 0) return w;
  w.median_rms_mm = std::sqrt(ss / double(n));
  w.between_mm2 = std::max(0.0, (ss - noise) / double(n));
  w.rays_per_cell = rays / double(n);
  w.design_effect = 1.0 + (w.rays_per_cell - 1.0) * w.between_mm2 / (w.between_mm2 + var);
  return w;
}

// The plates' mismatches [rad] at the state (unscaled), for their scatter.
std::vector<double> plateMismatches(const State& st) {
  std::vector<double> m;
  for (size_t s = 0; s < st.sweeps.size(); ++s) {
    const SweepState& ss = st.sweeps[s];
    if (!ss.plate) continue;
    m.push_back(wrapAngle(ss.beta - (st.alpha - ss.phi)));
  }
  return m;
}

// The problem's variable blocks: the nuisance (per sweep its attitude and planes) and the
// parameters (g, alpha), in the state's order.
void variableBlocks(Built* b, State* st, std::vector<double*>* nuisance,
                    std::vector<double*>* parameters) {
  const auto variable = [&](double* p) {
    return b->problem->HasParameterBlock(p) && !b->problem->IsParameterBlockConstant(p);
  };
  const auto add = [&](std::vector<double*>* to, double* p) {
    if (variable(p)) to->push_back(p);
  };
  for (SweepState& ss : st->sweeps) {
    add(nuisance, &ss.phi);
    for (size_t k = 0; k < ss.rays.size(); ++k) {
      if (ss.wall_class[k] >= 0) {
        add(nuisance, ss.wall[k].data());
      } else {
        add(nuisance, ss.normal[k].data());
        add(nuisance, &ss.distance[k]);
      }
    }
  }
  add(parameters, st->g);
  add(parameters, &st->alpha);
}

// Covariance of (alpha, x, tilt, mirror) in their own units (rad, mm, rad, rad), 0 for a held
// one (calib/parameter_information.hpp: a fixed order, the same bytes every run); NaN when it
// cannot be computed.
Eigen::Matrix4d covariance(Built* b, State* st) {
  Eigen::Matrix4d c = Eigen::Matrix4d::Constant(std::numeric_limits<double>::quiet_NaN());
  std::vector<double*> nuisance, parameters;
  variableBlocks(b, st, &nuisance, &parameters);
  // The parameters' tangent coordinates: g's free components in order, then alpha.
  const bool g_free = !parameters.empty() && parameters.front() == st->g;
  std::vector<int> index;
  for (int i = 0; i < 3; ++i) {
    if (g_free && !st->held[i + 1]) index.push_back(i + 1);
  }
  if (!parameters.empty() && parameters.back() == &st->alpha) index.push_back(0);
  const ParameterInformation info = eliminatedInformation(b->problem.get(), nuisance, parameters);
  if (!info.ok || info.information.rows() != Eigen::Index(index.size())) return c;
  const Eigen::MatrixXd t = covarianceFromInformation(info.information);
  if (!t.allFinite()) return c;
  c.setZero();
  for (size_t i = 0; i < index.size(); ++i) {
    for (size_t j = 0; j < index.size(); ++j)
      c(index[i], index[j]) = t(Eigen::Index(i), Eigen::Index(j));
  }
  return c;
}

}  // namespace

void takePlateCandidates(const std::vector<SweepRay>& rays, const RigAValues& v,
                         const PlateRegion& region, RigASweep* sweep) {
  const double g[3] = {v.offset_x_mm, v.tilt_deg * kDegToRad, v.mirror_deg * kDegToRad};
  const Eigen::Matrix3d R_L = rotating::lidarRotation(g[1], g[2]);
  std::vector<size_t> taken;
  for (size_t i = 0; i < rays.size(); ++i) {
    const SweepRay& r = rays[i];
    const Eigen::Matrix3d Rz = rotating::rotZ(r.phi_rad);
    if (plateRayRange(Rz * Eigen::Vector3d(1e-3 * g[0], 0, 0),
                      Rz * R_L * rotating::pointInLidar(1.0, r.theta_rad), region)) {
      taken.push_back(i);
    }
  }
  // Each ray by (scan, beam): its range, and its index among the candidates (-1: not one).
  const auto at = scanBeamOf(rays);
  long beams = 0;
  for (const auto& sb : at) beams = std::max(beams, sb.second + 1);
  long scans = 0;
  for (const auto& sb : at) scans = std::max(scans, sb.first + 1);
  std::vector<std::pair<float, int>> grid(size_t(scans * beams), {0.0f, -1});
  const auto cell = [&](long scan, long beam) { return size_t(scan * beams + beam); };
  for (size_t i = 0; i < rays.size(); ++i)
    grid[cell(at[i].first, at[i].second)].first = float(rays[i].range_m);
  for (size_t k = 0; k < taken.size(); ++k)
    grid[cell(at[taken[k]].first, at[taken[k]].second)].second = int(k);
  for (const size_t i : taken) {
    sweep->plate_rays.push_back(rays[i]);
    PlateRayBeams b;
    for (int side = 0; side < 2; ++side) {
      const long beam = at[i].second + (side ? 1 : -1);
      if (beam < 0 || beam >= beams) continue;
      b.range[size_t(side)] = grid[cell(at[i].first, beam)].first;
      b.next[size_t(side)] = grid[cell(at[i].first, beam)].second;
    }
    sweep->plate_beams.push_back(b);
  }
}

namespace {

// A sweep's plate rays placed with g, split by the side of the scan plane they leave the lidar
// on (the sign of sin theta): in a full turn each part of the plate is seen once from each
// side, and an offset or tilt error turns the two views opposite ways. With each ray its
// weight (plateHitWeights, given; empty: none).
struct PlateView {
  std::vector<PlateRay> rays;
  std::vector<double> weights;
  int hits = 0;
};

std::array<PlateView, 2> plateViews(const RigASweep& sweep, const std::vector<double>& weights,
                                    const double* g) {
  const std::vector<PlateRay> placed = placePlateRays(sweep.plate_rays, g);
  std::array<PlateView, 2> views;
  for (size_t i = 0; i < placed.size(); ++i) {
    PlateView& v = views[std::sin(sweep.plate_rays[i].theta_rad) < 0.0 ? 1 : 0];
    v.rays.push_back(placed[i]);
    if (weights.empty()) continue;
    v.weights.push_back(weights[i]);
    v.hits += weights[i] > 0.0;
  }
  return views;
}

// Each sweep's two views' angles in O' (fitPlateAgreeing) with the rays placed with g; nullopt
// for a view with fewer than min_plate_hits hits or no fit.
std::vector<std::array<std::optional<double>, 2>> viewAngles(const std::vector<RigASweep>& sweeps,
                                                             const RigASolveOptions& o,
                                                             const State& st, const double* g) {
  std::vector<std::array<std::optional<double>, 2>> out(st.sweeps.size());
  for (size_t s = 0; s < st.sweeps.size(); ++s) {
    const SweepState& ss = st.sweeps[s];
    if (!ss.plate) continue;
    const auto views = plateViews(sweeps[s], ss.plate_hits, g);
    for (size_t v = 0; v < 2; ++v) {
      if (views[v].hits < o.min_plate_hits) continue;
      out[s][v] = fitPlateAgreeing(o.plate, views[v].rays, views[v].weights, st.alpha - ss.phi);
    }
  }
  return out;
}

// The mean over the sweeps that show both views of view 0's angle minus view 1's by the smooth
// model (fitPlateModel, for its derivative); nullopt when no sweep shows both.
std::optional<double> viewDisagreement(const std::vector<RigASweep>& sweeps,
                                       const RigASolveOptions& o, const State& st,
                                       const double* g) {
  double sum = 0.0;
  int n = 0;
  for (size_t s = 0; s < st.sweeps.size(); ++s) {
    if (!st.sweeps[s].plate) continue;
    const auto views = plateViews(sweeps[s], st.sweeps[s].plate_hits, g);
    if (views[0].hits < o.min_plate_hits || views[1].hits < o.min_plate_hits) continue;
    const PlateModelFit f0 = fitPlateModel(o.plate, views[0].rays, o.min_plate_hits);
    const PlateModelFit f1 = fitPlateModel(o.plate, views[1].rays, o.min_plate_hits);
    if (!f0.found || !f1.found) continue;
    sum += f0.angle_rad - f1.angle_rad;
    ++n;
  }
  if (n == 0) return std::nullopt;
  return sum / n;
}

// How the views' disagreement moves with the offset [rad/mm] (~ -2 / 78 mm: each view turns by
// the offset over the plate's distance, the two opposite ways), by central differences of the
// smooth model; 0 when the sweeps do not show both views.
double viewsPerOffset(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o,
                      const State& st, const double* g) {
  const double step = 0.01;  // mm
  double gp[3], gm[3];
  std::copy(g, g + 3, gp);
  std::copy(g, g + 3, gm);
  gp[0] += step;
  gm[0] -= step;
  const auto p = viewDisagreement(sweeps, o, st, gp), m = viewDisagreement(sweeps, o, st, gm);
  return p && m ? (*p - *m) / (2 * step) : 0.0;
}

// The plates seen with the walls' g, the offset shifted to where the plate's two views agree:
// g_plate <- g (+ the shift) and each sweep's plate angle in O' again (fitPlateAgreeing, all
// its rays). In a full turn each part of the plate is seen from both sides of the scan plane;
// an offset error turns the two views opposite ways (so would an error of the plate's height,
// by the offset over its depth below the lidar: 1 mm of height ~0.3 mm of offset), so the
// plate's angle does not move with it to first order, but each view's angle moves by the steps
// at which its rays flip (0.57-0.94 deg/mm on seed 3, the mean 0.72): with the walls' 0.1 mm
// offset error the mean of the two views scattered by 0.011 deg per sweep, at the true offset
// by 0.004 deg. The views agree within 0.001 mm of the true offset on seed 3 of the plan's
// recording, but cannot tell an offset from a height error: the shift serves the plate only, the
// walls alone give the offset.
// The most the plate's views may move the offset they are placed with [mm]: 20 sigma of the
// walls' offset on the plan's recording; beyond, the model lacks something (warnPlateShift).
constexpr double kMaxPlateShiftMm = 2.0;

void placePlates(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o, State* st) {
  std::copy(st->g, st->g + 3, st->g_plate);
  st->g_plate[0] += st->plate_shift_mm;
  auto angles = viewAngles(sweeps, o, *st, st->g_plate);
  for (int i = 0; i < 3; ++i) {
    double sum = 0.0;
    int n = 0;
    for (const auto& a : angles) {
      if (a[0] && a[1]) sum += *a[0] - *a[1], ++n;
    }
    if (n == 0) break;
    if (st->views_per_offset == 0.0)
      st->views_per_offset = viewsPerOffset(sweeps, o, *st, st->g_plate);
    if (!(std::fabs(st->views_per_offset) > 1e-6)) break;
    const double shift = std::clamp(st->plate_shift_mm - (sum / n) / st->views_per_offset,
                                    -kMaxPlateShiftMm, kMaxPlateShiftMm) -
                         st->plate_shift_mm;
    if (std::fabs(shift) < 1e-3) break;
    st->plate_shift_mm += shift;
    st->g_plate[0] += shift;
    angles = viewAngles(sweeps, o, *st, st->g_plate);
  }
  for (size_t s = 0; s < st->sweeps.size(); ++s) {
    SweepState& ss = st->sweeps[s];
    if (!ss.plate) continue;
    const auto& a = angles[s];
    const double start = a[0] && a[1] ? 0.5 * (*a[0] + *a[1])
                         : a[0]       ? *a[0]
                         : a[1]       ? *a[1]
                                      : st->alpha - ss.phi;
    const auto beta = fitPlateAgreeing(o.plate, placePlateRays(sweeps[s].plate_rays, st->g_plate),
                                       ss.plate_hits, start);
    if (beta || a[0] || a[1]) ss.beta = beta ? *beta : start;
  }
}

State initState(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o) {
  State st;
  st.g[0] = o.nominal.offset_x_mm;
  st.g[1] = o.nominal.tilt_deg * kDegToRad;
  st.g[2] = o.nominal.mirror_deg * kDegToRad;
  st.alpha = o.nominal.alpha_deg * kDegToRad;
  for (const RigASweep& s : sweeps) st.sweeps.push_back(initSweep(s, o, st));
  placePlates(sweeps, o, &st);
  st.held[0] = std::none_of(st.sweeps.begin(), st.sweeps.end(),
                            [](const SweepState& ss) { return ss.plate; });
  return st;
}

// The table of the four, in the rig file's keys and units, from the state and the covariance
// (alpha, x, tilt, mirror in rad, mm, rad, rad).
std::vector<CalibParameter> parameterTable(const State& st, const RigASolveOptions& o) {
  const double d = kRadToDeg;
  std::vector<CalibParameter> p = {
      {"plate.alpha_deg", st.alpha * d, 0, "deg", true, o.truth.alpha_deg, o.nominal.alpha_deg, ""},
      {"geometry.lidar_offset_x_mm", st.g[0], 0, "mm", true, o.truth.offset_x_mm,
       o.nominal.offset_x_mm, ""},
      {"geometry.scan_plane_tilt_deg", st.g[1] * d, 0, "deg", true, o.truth.tilt_deg,
       o.nominal.tilt_deg, ""},
      {"geometry.mirror_offset_deg", st.g[2] * d, 0, "deg", true, o.truth.mirror_deg,
       o.nominal.mirror_deg, ""}};
  return p;
}

Eigen::Matrix4d inUnits(const Eigen::Matrix4d& c) {
  const Eigen::Vector4d s(kRadToDeg, 1.0, kRadToDeg, kRadToDeg);
  return s.asDiagonal() * c * s.asDiagonal();
}

// The plates' measured hits again with a range gate of kPlateGateSigmas of the range noise (the
// rig's gate if wider): with 12 mm of noise the rig's 30 mm gate left 1.2 % of the plate's
// rays out at random, whose centroid then scattered by ~0.02 deg per sweep.
constexpr double kPlateGateSigmas = 5.0;

void weighPlateHits(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o, State* st) {
  PlateModel m = o.plate;
  m.range_gate_m = std::max(m.range_gate_m, kPlateGateSigmas * 1e-3 * st->sigma_mm);
  for (size_t s = 0; s < st->sweeps.size(); ++s) {
    SweepState& ss = st->sweeps[s];
    if (!ss.plate) continue;
    ss.plate_hits =
        plateHitWeights(m, placePlateRays(sweeps[s].plate_rays, st->g), sweeps[s].plate_beams);
  }
}

// Stage 2's weights: the points' robust sigma, the walls' clutter out, the plates' angles with
// the walls' g and their scatter.
void reweigh(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o, State* st) {
  st->sigma_mm = robustSigma(keptResiduals(*st));
  removeClutter(o, st);
  weighPlateHits(sweeps, o, st);
  placePlates(sweeps, o, st);
  const std::vector<double> m = plateMismatches(*st);
  // Their scatter about their mean (alpha takes the mean), robustly; Cauchy from now on.
  if (m.size() >= 2) {
    double mean = 0.0;
    for (const double v : m) mean += v / double(m.size());
    std::vector<double> centred;
    for (const double v : m) centred.push_back(v - mean);
    double ss = 0.0;
    for (const double v : centred) ss += v * v;
    const double sd = std::sqrt(ss / double(m.size() - 1));
    st->sigma_plate_rad = std::max(1e-5, m.size() >= 5 ? std::min(sd, robustSigma(centred)) : sd);
    st->plate_robust = true;
  }
}

// Holds the flagged parameters at the rig's values.
void holdAtNominal(const std::vector<size_t>& flagged, const RigASolveOptions& o, State* st) {
  for (const size_t i : flagged) {
    st->held[i] = true;
    if (i == 0) st->alpha = o.nominal.alpha_deg * kDegToRad;
    if (i == 1) st->g[0] = o.nominal.offset_x_mm;
    if (i == 2) st->g[1] = o.nominal.tilt_deg * kDegToRad;
    if (i == 3) st->g[2] = o.nominal.mirror_deg * kDegToRad;
  }
}

// Warnings for what the model does not explain: residuals above the noise, structured walls,
// scattered plates.
void checkResiduals(const RigASolveOptions& o, State* st, RigCalibration* r) {
  std::ostringstream w;
  if (r->rms_after > 1.3 * st->sigma_mm) {
    w << "the residuals after calibration (RMS " << r->rms_after << " mm) exceed their robust "
      << "sigma (" << st->sigma_mm << " mm) by more than noise does: an error the model lacks";
    r->warnings.push_back(w.str());
    w.str("");
  }
  const WallCells cells = wallCells(o, *st);
  if (cells.median_rms_mm > o.systematic_limit_mm) {
    w << "the walls still disagree with their planes by " << cells.median_rms_mm
      << " mm RMS over 0.5 m cells after calibration (noise alone: under " << o.systematic_limit_mm
      << " mm): an error the model lacks (a bent wall, another rig "
      << "error); the sigmas are grown by " << std::sqrt(cells.design_effect)
      << "x for it, but an error the model lacks also moves the values";
    r->warnings.push_back(w.str());
    w.str("");
  }
  if (st->sigma_plate_rad * kRadToDeg > 0.05) {
    w << "the plate's angle scatters by " << st->sigma_plate_rad * kRadToDeg
      << " deg from sweep to sweep: the plate model does not fit it (a loose plate, clutter "
      << "on it, a wrong plate.height_mm or thickness_mm)";
    r->warnings.push_back(w.str());
  }
}

// A warning when alpha moves with the offset (each plate seen from one side of the scan
// plane: half turns), naming what separates them.
// The plate's two views agree at an offset the walls do not give (beyond 3 sigma of theirs,
// or at the clamp): the plate's height, thickness or the offset differ from the model.
void warnPlateShift(const State& st, double offset_sigma_mm, RigCalibration* r) {
  if (!(std::fabs(st.plate_shift_mm) > 3.0 * offset_sigma_mm)) return;
  std::ostringstream w;
  w << "the plate's two views agree at an offset " << st.plate_shift_mm
    << " mm from the walls' (sigma " << offset_sigma_mm
    << " mm): the plate's height or thickness in the rig file, or the offset, differs from the "
       "model; alpha is placed with the views' offset"
    << (std::fabs(st.plate_shift_mm) >= kMaxPlateShiftMm ? " (held at its limit)" : "");
  r->warnings.push_back(w.str());
}

void warnOneSidedPlate(RigCalibration* r) {
  if (r->correlation.rows() < 2 || !r->parameters[0].observable || !r->parameters[1].observable) {
    return;
  }
  const double c = r->correlation(0, 1);
  if (!(std::fabs(c) > 0.9)) return;
  std::ostringstream w;
  w << "plate.alpha_deg moves with geometry.lidar_offset_x_mm (correlation " << c
    << "): the sweeps saw each part of the plate from one side of the scan plane, where an "
       "offset turns it; alpha's sigma is the offset's times ~0.73 deg/mm. Sweeps of a full "
       "turn (sweepmap calib plan) see it from both sides and separate the two";
  r->warnings.push_back(w.str());
}

// alpha as the plates give it with the rays placed with g, the sweeps' attitudes held: the
// mean of phi_s + the plate's angle in O' (the offset shifted to where its views agree, as
// placePlates). By the smooth model (fitPlateModel): its angle moves with g as the plate's does,
// where the agreeing estimator's steps would make the difference quotient below noise.
double alphaFromPlates(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o,
                       const State& st, const double* g) {
  double sum = 0.0;
  int n = 0;
  for (size_t s = 0; s < st.sweeps.size(); ++s) {
    const SweepState& ss = st.sweeps[s];
    if (!ss.plate) continue;
    const double gs[3] = {g[0] + st.plate_shift_mm, g[1], g[2]};
    const PlateModelFit f =
        fitPlateModel(o.plate, placePlateRays(sweeps[s].plate_rays, gs), o.min_plate_hits);
    if (!f.found) continue;
    sum += ss.phi + f.angle_rad;
    ++n;
  }
  return n ? sum / n : st.alpha;
}

// g's uncertainty into alpha's (raw units): J = d alpha / d g by central differences,
// C_aa += J C_gg J^T, C_ag = J C_gg.
void propagateToAlpha(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o,
                      const State& st, Eigen::Matrix4d* c) {
  const Eigen::Matrix3d cgg = c->bottomRightCorner<3, 3>();
  if (!cgg.allFinite() || st.held[0]) return;
  const double steps[3] = {1e-3, 1e-5, 1e-5};  // mm, rad, rad
  Eigen::RowVector3d J = Eigen::RowVector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    if (st.held[i + 1]) continue;
    double gp[3] = {}, gm[3] = {};
    std::copy(st.g, st.g + 3, gp);
    std::copy(st.g, st.g + 3, gm);
    gp[i] += steps[i];
    gm[i] -= steps[i];
    J(i) =
        (alphaFromPlates(sweeps, o, st, gp) - alphaFromPlates(sweeps, o, st, gm)) / (2 * steps[i]);
  }
  (*c)(0, 0) += J * cgg * J.transpose();
  const Eigen::RowVector3d cag = J * cgg;
  for (int i = 0; i < 3; ++i) (*c)(0, i + 1) = (*c)(i + 1, 0) = cag(i);
}

// The covariance of the four in the rig file's units at the solution: the problem's, grown
// by the walls' design effect (rays that share their cell's unmodelled error are not
// independent), with g's uncertainty propagated into alpha's.
Eigen::Matrix4d parameterCovariance(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o,
                                    Built* b, State* st) {
  Eigen::Matrix4d raw = covariance(b, st);
  const WallCells cells = wallCells(o, *st);
  raw *= cells.design_effect;
  propagateToAlpha(sweeps, o, *st, &raw);
  return inUnits(raw);
}

}  // namespace

RigCalibration solveRigA(const std::vector<RigASweep>& sweeps, const RigASolveOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  size_t planes = 0;
  for (const auto& s : sweeps) planes += s.planes.size();
  if (planes == 0) throw std::invalid_argument("rig A calibration: no sweep with planes");
  RigCalibration r;
  State st = initState(sweeps, o);
  const std::vector<double> e0 = keptResiduals(st);
  st.sigma_mm = robustSigma(e0);
  r.rms_before = inlierRms(e0, st.sigma_mm);
  {
    Built b = buildProblem(sweeps, o, &st);
    solve(o, &b);
  }
  reweigh(sweeps, o, &st);
  Built b = buildProblem(sweeps, o, &st);
  if (!solve(o, &b)) r.warnings.push_back("the solver stopped before converging");
  // The plates once more with the final g.
  placePlates(sweeps, o, &st);
  solve(o, &b);
  Eigen::Matrix4d cov = parameterCovariance(sweeps, o, &b, &st);
  r.parameters = parameterTable(st, o);
  ObservabilityLimits limits{o.max_sigma};
  std::vector<size_t> flagged = testObservability(cov, limits, &r.parameters);
  for (size_t i = 0; i < kParams; ++i) {
    if (st.held[i] && r.parameters[i].observable) flagged.push_back(i);
  }
  if (!flagged.empty()) {
    const std::vector<CalibParameter> first = r.parameters;
    holdAtNominal(flagged, o, &st);
    Built b2 = buildProblem(sweeps, o, &st);
    solve(o, &b2);
    placePlates(sweeps, o, &st);
    solve(o, &b2);
    cov = parameterCovariance(sweeps, o, &b2, &st);
    r.parameters = parameterTable(st, o);
    for (size_t i = 0; i < kParams; ++i) {
      r.parameters[i].sigma = std::sqrt(cov(Eigen::Index(i), Eigen::Index(i)));
      r.parameters[i].observable = !st.held[i];
      r.parameters[i].note =
          first[i].note.empty() && st.held[i] ? "no sweep saw the plate" : first[i].note;
      if (st.held[i]) r.parameters[i].sigma = std::numeric_limits<double>::quiet_NaN();
    }
  }
  for (const auto& p : r.parameters) {
    if (!p.observable) {
      r.warnings.push_back(p.key + " is not observable from these logs (" + p.note +
                           "): left at the rig's " + std::to_string(p.nominal) + " " + p.unit);
    }
  }
  r.correlation = correlationOf(cov);
  r.rms_after = inlierRms(keptResiduals(st), st.sigma_mm);
  checkResiduals(o, &st, &r);
  warnOneSidedPlate(&r);
  warnPlateShift(st, std::sqrt(cov(1, 1)), &r);
  r.sweeps_used = int(sweeps.size());
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace sweepmap
