#include "calib/axis_offset_lidar.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "calib/parameter_information.hpp"
#include "calib/rotating_geometry.hpp"
#include "calib/walls.hpp"

namespace sweepmap {
namespace {

using Clock = std::chrono::steady_clock;
constexpr size_t kRaysPerBlock = 64;

// A ray in the form the residual needs: cos, sin of phi and p_L [mm].
struct PreRay {
  double c, s, px, py, pz;  // R_L p_L = (px, py, pz) [mm]
};

PreRay pre(const SweepRay& r, const Eigen::Matrix3d& R_L) {
  const Eigen::Vector3d p = R_L * rotating::pointInLidar(1e3 * r.range_m, r.theta_rad);
  return {std::cos(r.phi_rad), std::sin(r.phi_rad), p.x(), p.y(), p.z()};
}

// Up to kRaysPerBlock rays of one plane: residual sqrt(w_i) (n . Rz(phi_i) (t + R_L p_L,i) - d)
// [mm] each, the weights w_i (Cauchy, iteratively reweighted) read from `weights`, analytic
// Jacobians. Parameters: t 3 [mm], unit normal 3, distance 1 [mm].
class RaysOnPlaneCost : public ceres::CostFunction {
 public:
  RaysOnPlaneCost(const PreRay* first, const double* weights, size_t count)
      : rays_(first), weights_(weights), count_(count) {
    set_num_residuals(static_cast<int>(count));
    *mutable_parameter_block_sizes() = {3, 3, 1};
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* t = parameters[0];
    const double* n = parameters[1];
    const double d = parameters[2][0];
    for (size_t i = 0; i < count_; ++i) {
      const PreRay& r = rays_[i];
      const double sw = std::sqrt(weights_[i]);
      const double qx = t[0] + r.px, qy = t[1] + r.py, qz = t[2] + r.pz;
      const double px = r.c * qx - r.s * qy, py = r.s * qx + r.c * qy;
      residuals[i] = sw * (n[0] * px + n[1] * py + n[2] * qz - d);
      if (!jacobians) continue;
      if (jacobians[0]) {  // Rz(phi)^T n
        jacobians[0][3 * i] = sw * (r.c * n[0] + r.s * n[1]);
        jacobians[0][3 * i + 1] = sw * (-r.s * n[0] + r.c * n[1]);
        jacobians[0][3 * i + 2] = sw * n[2];
      }
      if (jacobians[1]) {
        jacobians[1][3 * i] = sw * px;
        jacobians[1][3 * i + 1] = sw * py;
        jacobians[1][3 * i + 2] = sw * qz;
      }
      if (jacobians[2]) jacobians[2][i] = -sw;
    }
    return true;
  }

 private:
  const PreRay* rays_;
  const double* weights_;
  size_t count_;
};

// The least-squares plane through the rays placed with `t`, normal oriented as `hint` (if
// given) and its points' RMS distance [mm].
struct PlaneFit {
  Eigen::Vector3d normal;
  double distance_mm = 0.0;
  double rms_mm = 0.0;
  bool ok = false;
};

PlaneFit fitPlaneTo(const std::vector<SweepRay>& rays, const Eigen::Vector3d& t_mm,
                    const Eigen::Matrix3d& R_L) {
  std::vector<Eigen::Vector3f> pts;  // metres: what fitPlaneLeastSquares is made for
  pts.reserve(rays.size());
  std::vector<int> idx;
  for (const auto& r : rays) {
    idx.push_back(static_cast<int>(pts.size()));
    pts.push_back((placeRayMm(r, t_mm, R_L) * 1e-3).cast<float>());
  }
  PlaneFit f;
  double offset_m = 0.0;
  if (!fitPlaneLeastSquares(pts, idx, &f.normal, &offset_m)) return f;
  f.distance_mm = -1e3 * offset_m;
  double ss = 0.0;
  for (const auto& r : rays) {
    const double e = f.normal.dot(placeRayMm(r, t_mm, R_L)) - f.distance_mm;
    ss += e * e;
  }
  f.rms_mm = std::sqrt(ss / static_cast<double>(rays.size()));
  f.ok = true;
  return f;
}

// The problem's state: the offset and one (normal, distance) per plane, the rays prepared
// and their weights.
struct LidarProblem {
  double t[3];
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> distances;
  std::vector<std::vector<PreRay>> rays;
  std::vector<std::vector<double>> weights;
  std::unique_ptr<ceres::Problem> problem;
  size_t residuals = 0;
};

void buildProblem(const std::vector<LidarPlaneRays>& planes, const LidarAxisOffsetOptions& o,
                  LidarProblem* p) {
  for (int k = 0; k < 3; ++k) p->t[k] = o.initial_offset_mm[k];
  ceres::Problem::Options po;
  po.manifold_ownership = ceres::TAKE_OWNERSHIP;
  p->problem = std::make_unique<ceres::Problem>(po);
  p->normals.resize(planes.size());
  p->distances.resize(planes.size());
  p->rays.resize(planes.size());
  p->weights.resize(planes.size());
  for (size_t k = 0; k < planes.size(); ++k) {
    const PlaneFit f = fitPlaneTo(planes[k].rays, o.initial_offset_mm, o.lidar_rotation);
    p->normals[k] = f.ok ? f.normal : Eigen::Vector3d::UnitZ();
    p->distances[k] = f.distance_mm;
    for (const auto& r : planes[k].rays) p->rays[k].push_back(pre(r, o.lidar_rotation));
    p->weights[k].assign(p->rays[k].size(), 1.0);
    for (size_t i = 0; i < p->rays[k].size(); i += kRaysPerBlock) {
      const size_t count = std::min(kRaysPerBlock, p->rays[k].size() - i);
      p->problem->AddResidualBlock(new RaysOnPlaneCost(&p->rays[k][i], &p->weights[k][i], count),
                                   nullptr, p->t, p->normals[k].data(), &p->distances[k]);
      p->residuals += count;
    }
    p->problem->SetManifold(p->normals[k].data(), new ceres::SphereManifold<3>());
  }
  std::vector<int> held = {2};  // z: the planes' distances absorb it (never observable)
  if (!o.estimate_y) held.insert(held.begin(), 1);
  p->problem->SetManifold(p->t, new ceres::SubsetManifold(3, held));
}

// Every ray's residual [mm] (unweighted) at the current state.
std::vector<double> residualsOf(const LidarProblem& p) {
  std::vector<double> out;
  out.reserve(p.residuals);
  for (size_t k = 0; k < p.rays.size(); ++k) {
    const Eigen::Vector3d& n = p.normals[k];
    for (const PreRay& r : p.rays[k]) {
      const double qx = p.t[0] + r.px, qy = p.t[1] + r.py, qz = p.t[2] + r.pz;
      out.push_back(n.x() * (r.c * qx - r.s * qy) + n.y() * (r.s * qx + r.c * qy) + n.z() * qz -
                    p.distances[k]);
    }
  }
  return out;
}

// Robust sigma of the residuals: 1.4826 x their median absolute value.
double robustSigma(std::vector<double> e) {
  for (double& v : e) v = std::fabs(v);
  std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
  return 1.4826 * e[e.size() / 2];
}

void setCauchyWeights(double scale_mm, LidarProblem* p) {
  const std::vector<double> e = residualsOf(*p);
  size_t i = 0;
  for (auto& w : p->weights) {
    for (double& v : w) {
      const double u = e[i++] / scale_mm;
      v = 1.0 / (1.0 + u * u);
    }
  }
}

// Which components of t the planes determine: per plane, the QR of its rows [the plane's
// tangent columns (e1 . p, e2 . p, -1) | the t columns (Rz^T n)] leaves the t columns with
// the plane eliminated (R22, 3 x 3); stacked over the planes and factorised again they give
// the whole problem's t information with every plane eliminated, without forming the dense
// Jacobian. Scaled by sqrt(sum of the weights): the column of a component that moved every
// point straight off its plane (|Rz^T n| = 1 is the most a component can do), so a share is
// the RMS distance [mm] that 1 mm of the component moves the points off the planes once the
// planes have adjusted to it.
struct TObservability {
  Eigen::Vector3d share = Eigen::Vector3d::Zero();  // per component alone
  Eigen::Matrix3d r22 = Eigen::Matrix3d::Zero();    // joint, unscaled
  double scale = 0.0;                               // sqrt(sum of the weights)
};

TObservability analyse(const LidarProblem& p) {
  std::vector<Eigen::Matrix3d> blocks;
  double weights = 0.0;
  for (size_t k = 0; k < p.rays.size(); ++k) {
    const Eigen::Vector3d& n = p.normals[k];
    // A tangent basis of the sphere at n.
    const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
    const auto rows = static_cast<Eigen::Index>(p.rays[k].size());
    if (rows < 6) continue;
    Eigen::MatrixXd j(rows, 6);
    for (Eigen::Index i = 0; i < rows; ++i) {
      const PreRay& r = p.rays[k][static_cast<size_t>(i)];
      const double sw = std::sqrt(p.weights[k][static_cast<size_t>(i)]);
      const double qx = p.t[0] + r.px, qy = p.t[1] + r.py, qz = p.t[2] + r.pz;
      const Eigen::Vector3d pt(r.c * qx - r.s * qy, r.s * qx + r.c * qy, qz);
      j.row(i) << sw * e1.dot(pt), sw * e2.dot(pt), -sw, sw * (r.c * n.x() + r.s * n.y()),
          sw * (-r.s * n.x() + r.c * n.y()), sw * n.z();
    }
    for (const double w : p.weights[k]) weights += w;
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(j);
    blocks.push_back(
        qr.matrixQR().topRows(6).triangularView<Eigen::Upper>().toDenseMatrix().bottomRightCorner(
            3, 3));
  }
  TObservability o;
  o.scale = std::sqrt(weights);
  if (blocks.empty() || !(o.scale > 0)) return o;
  Eigen::MatrixXd stacked(3 * static_cast<Eigen::Index>(blocks.size()), 3);
  for (size_t b = 0; b < blocks.size(); ++b) {
    stacked.middleRows(3 * static_cast<Eigen::Index>(b), 3) = blocks[b];
  }
  for (int c = 0; c < 3; ++c) o.share[c] = stacked.col(c).norm() / o.scale;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(stacked);
  o.r22 = qr.matrixQR().topRows(3).triangularView<Eigen::Upper>();
  return o;
}

// The joint scaled singular values of the estimated components; a warning and observable =
// false when x (or y, if estimated) is not determined.
void flagUnobservable(const TObservability& obs, const LidarAxisOffsetOptions& o, size_t wall_count,
                      LidarAxisOffsetResult* r) {
  r->observability = obs.share;
  std::vector<int> est = {0};
  if (o.estimate_y) est.push_back(1);
  Eigen::MatrixXd m(3, est.size());
  for (size_t c = 0; c < est.size(); ++c) {
    m.col(static_cast<Eigen::Index>(c)) =
        obs.scale > 0 ? Eigen::Vector3d(obs.r22.col(est[c]) / obs.scale) : Eigen::Vector3d::Zero();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(m);
  r->smallest_singular_value = svd.singularValues().minCoeff();
  if (r->smallest_singular_value > o.min_observability) return;
  std::ostringstream w;
  w << "the offset perpendicular to the axis is not observable from these planes (scaled "
       "singular value "
    << r->smallest_singular_value << ")";
  if (wall_count == 0) {
    w << ": no plane is parallel to the axis (a vertical wall); planes perpendicular to it "
         "(floor, ceiling) constrain only the offset along the axis, which no plane can see";
  }
  r->warnings.push_back(w.str());
  r->observable = false;
}

// Standard deviations of x (and y): the inverse of J^T J of the offset with the planes
// eliminated (calib/parameter_information.hpp, in a fixed order), scaled by the weighted
// residuals' variance.
void standardDeviations(const LidarAxisOffsetOptions& o, size_t plane_count, LidarProblem* p,
                        LidarAxisOffsetResult* r) {
  if (!r->observable) return;
  ceres::Problem::EvaluateOptions eo;
  double cost = 0.0;
  p->problem->Evaluate(eo, &cost, nullptr, nullptr, nullptr);
  const double dof = static_cast<double>(p->residuals) - (o.estimate_y ? 2.0 : 1.0) -
                     3.0 * static_cast<double>(plane_count);
  const double variance = 2.0 * cost / std::max(1.0, dof);
  std::vector<double*> planes;
  for (size_t k = 0; k < p->normals.size(); ++k) {
    planes.push_back(p->normals[k].data());
    planes.push_back(&p->distances[k]);
  }
  // The offset's tangent coordinates: x, then y when it is estimated (z is held).
  const Eigen::MatrixXd c = covarianceFromInformation(
      eliminatedInformation(p->problem.get(), planes, {p->t}).information);
  if (c.size() == 0 || !c.allFinite()) {
    r->warnings.push_back("the covariance is singular: no standard deviations");
    r->observable = false;
    return;
  }
  r->sigma_x_mm = std::sqrt(c(0, 0) * variance);
  if (o.estimate_y) r->sigma_y_mm = std::sqrt(c(1, 1) * variance);
  if (r->sigma_x_mm > o.max_sigma_mm) {
    std::ostringstream w;
    w << "the offset is poorly determined by these planes: sigma " << r->sigma_x_mm << " mm > "
      << o.max_sigma_mm << " mm";
    r->warnings.push_back(w.str());
    r->observable = false;
  }
}

// Sums of squares for an RMS, over every plane and over the walls.
struct RmsSums {
  double all = 0, walls = 0;
  size_t n = 0, wall_n = 0;
  void add(double rms, size_t count, bool wall) {
    const double ss = rms * rms * static_cast<double>(count);
    all += ss;
    n += count;
    if (wall) {
      walls += ss;
      wall_n += count;
    }
  }
  static double rms(double ss, size_t count) {
    return std::sqrt(ss / static_cast<double>(std::max<size_t>(1, count)));
  }
};

// Each plane refit by least squares with the nominal and the estimated offset; the RMS over
// every plane and over the walls, of all their points and of the inliers (the points within
// the Cauchy scale of their plane at the solution: the same points before and after).
void reportPlanes(const std::vector<LidarPlaneRays>& planes, const LidarProblem& p,
                  const LidarAxisOffsetOptions& o, LidarAxisOffsetResult* r) {
  RmsSums before, after, in_before, in_after;
  const std::vector<double> e = residualsOf(p);
  size_t next = 0;
  for (size_t k = 0; k < planes.size(); ++k) {
    LidarFittedPlane f;
    f.source = planes[k].source;
    f.normal = p.normals[k];
    f.distance_mm = p.distances[k];
    f.rays = planes[k].rays.size();
    f.wall = std::fabs(f.normal.z()) <= o.wall_max_normal_z;
    f.rms_before_mm = fitPlaneTo(planes[k].rays, o.initial_offset_mm, o.lidar_rotation).rms_mm;
    f.rms_after_mm = fitPlaneTo(planes[k].rays, r->offset_mm, o.lidar_rotation).rms_mm;
    before.add(f.rms_before_mm, f.rays, f.wall);
    after.add(f.rms_after_mm, f.rays, f.wall);
    std::vector<SweepRay> inliers;
    for (const SweepRay& ray : planes[k].rays) {
      if (std::fabs(e[next++]) <= r->cauchy_scale_mm) inliers.push_back(ray);
    }
    if (inliers.size() >= 3) {
      in_before.add(fitPlaneTo(inliers, o.initial_offset_mm, o.lidar_rotation).rms_mm,
                    inliers.size(), f.wall);
      in_after.add(fitPlaneTo(inliers, r->offset_mm, o.lidar_rotation).rms_mm, inliers.size(),
                   f.wall);
    }
    if (f.wall) ++r->walls;
    r->planes.push_back(f);
  }
  r->rms_before_mm = RmsSums::rms(before.all, before.n);
  r->rms_after_mm = RmsSums::rms(after.all, after.n);
  r->wall_rms_before_mm = RmsSums::rms(before.walls, before.wall_n);
  r->wall_rms_after_mm = RmsSums::rms(after.walls, after.wall_n);
  r->wall_inlier_rms_before_mm = RmsSums::rms(in_before.walls, in_before.wall_n);
  r->wall_inlier_rms_after_mm = RmsSums::rms(in_after.walls, in_after.wall_n);
  r->wall_inliers = in_after.wall_n;
}

}  // namespace

Eigen::Vector3d placeRayMm(const SweepRay& ray, const Eigen::Vector3d& offset_mm,
                           const Eigen::Matrix3d& R_L) {
  return rotating::lidarToOPrime(R_L * rotating::pointInLidar(1e3 * ray.range_m, ray.theta_rad),
                                 ray.phi_rad, offset_mm);
}

std::vector<std::pair<long, long>> scanBeamOf(const std::vector<SweepRay>& rays) {
  std::vector<std::pair<long, long>> at(rays.size());
  if (rays.empty()) return at;
  if (std::all_of(rays.begin(), rays.end(),
                  [](const SweepRay& r) { return r.scan >= 0 && r.beam >= 0; })) {
    for (size_t i = 0; i < rays.size(); ++i) at[i] = {rays[i].scan, rays[i].beam};
    return at;
  }
  double step = std::numeric_limits<double>::infinity(), lowest = rays[0].theta_rad;
  for (size_t i = 0; i < rays.size(); ++i) {
    lowest = std::min(lowest, rays[i].theta_rad);
    const double d = i ? rays[i].theta_rad - rays[i - 1].theta_rad : 0.0;
    if (d > 1e-9) step = std::min(step, d);
  }
  if (!std::isfinite(step)) step = 1.0;
  long scan = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (i && !(rays[i].theta_rad > rays[i - 1].theta_rad)) ++scan;
    at[i] = {scan, std::lround((rays[i].theta_rad - lowest) / step)};
  }
  return at;
}

namespace {

// Takes out of `owner` every ray within `m` beams and scans of a valid ray that is not of
// its plane (owner -1: no plane or an edge; another plane).
void dropDepthEdges(const std::vector<SweepRay>& rays, int m, std::vector<int>* owner) {
  if (m <= 0 || rays.empty()) return;
  const auto at = scanBeamOf(rays);
  long scans = 0, beams = 0;
  for (const auto& [scan, beam] : at) {
    scans = std::max(scans, scan + 1);
    beams = std::max(beams, beam + 1);
  }
  // The owner of each (scan, beam); -2: no valid ray there.
  std::vector<int> grid(size_t(scans * beams), -2);
  for (size_t i = 0; i < rays.size(); ++i) {
    grid[size_t(at[i].first * beams + at[i].second)] = (*owner)[i];
  }
  for (size_t i = 0; i < rays.size(); ++i) {
    const int mine = (*owner)[i];
    if (mine < 0) continue;
    bool inside = true;
    for (long s = std::max(0L, at[i].first - m); s <= std::min(scans - 1, at[i].first + m); ++s) {
      for (long b = std::max(0L, at[i].second - m); b <= std::min(beams - 1, at[i].second + m);
           ++b) {
        const int other = grid[size_t(s * beams + b)];
        inside = inside && (other == -2 || other == mine);
      }
    }
    if (!inside) (*owner)[i] = -1;
  }
}

}  // namespace

std::vector<LidarPlaneRays> segmentSweepPlanes(const std::vector<Eigen::Vector3f>& points_Op,
                                               const std::vector<SweepRay>& rays,
                                               const PlaneSegmentationOptions& o,
                                               const std::string& source) {
  if (points_Op.size() != rays.size()) {
    throw std::invalid_argument("segmentSweepPlanes: " + source + ": " +
                                std::to_string(points_Op.size()) + " points but " +
                                std::to_string(rays.size()) + " rays");
  }
  PlaneExtractionOptions po;
  po.orientation = PlaneExtractionOptions::Orientation::kAny;
  po.voxel_m = o.voxel_m;
  po.distance_threshold_m = o.ransac_distance_m;
  po.max_planes = o.max_planes;
  po.min_inliers = o.min_inliers;
  const std::vector<WallPlaneFit> found = extractPlanes(points_Op, po);
  // Each ray to the plane whose crossing along the ray its range is within the gate of, if
  // no other plane crosses the ray within `edge_margin` of that one (edges, corners: none).
  // The edge rule depends on the ray and the planes alone, not on the range's noise, and the
  // gate cuts the noise symmetrically: the kept points' noise stays centred (deciding by
  // their noisy distances to two planes leaned the offset by ~0.1 mm).
  std::vector<int> owner(points_Op.size(), -1);
  std::vector<double> crossing(found.size());
  for (size_t i = 0; i < points_Op.size(); ++i) {
    const SweepRay& ray = rays[i];
    const Eigen::Vector3d u =
        rotating::rotZ(ray.phi_rad) * rotating::pointInLidar(1.0, ray.theta_rad);
    const Eigen::Vector3d origin = points_Op[i].cast<double>() - ray.range_m * u;
    int best = -1;
    for (size_t k = 0; k < found.size(); ++k) {
      const double nu = found[k].normal.dot(u);
      crossing[k] = nu != 0.0 ? -(found[k].normal.dot(origin) + found[k].offset) / nu
                              : std::numeric_limits<double>::infinity();
      if (std::fabs(crossing[k] - ray.range_m) <= o.assign_distance_m) best = static_cast<int>(k);
    }
    if (best < 0) continue;
    bool alone = true;
    for (size_t k = 0; k < found.size() && alone; ++k) {
      alone = static_cast<int>(k) == best ||
              !(std::fabs(crossing[k] - crossing[static_cast<size_t>(best)]) < o.edge_margin_m);
    }
    if (alone) owner[i] = best;
  }
  dropDepthEdges(rays, o.depth_edge_rays, &owner);
  std::vector<LidarPlaneRays> planes(found.size());
  for (size_t i = 0; i < owner.size(); ++i) {
    if (owner[i] >= 0) planes[static_cast<size_t>(owner[i])].rays.push_back(rays[i]);
  }
  std::vector<LidarPlaneRays> out;
  for (size_t k = 0; k < planes.size(); ++k) {
    LidarPlaneRays& p = planes[k];
    if (p.rays.size() < 3) continue;
    p.source = source + " plane " + std::to_string(k);
    if (o.max_rays_per_plane > 0) stridePlaneRays(size_t(o.max_rays_per_plane), &p);
    out.push_back(std::move(p));
  }
  return out;
}

void stridePlaneRays(size_t max_rays, LidarPlaneRays* plane) {
  if (max_rays == 0 || plane->rays.size() <= max_rays) return;
  const size_t stride = (plane->rays.size() + max_rays - 1) / max_rays;
  std::vector<SweepRay> kept;
  for (size_t i = 0; i < plane->rays.size(); i += stride) kept.push_back(plane->rays[i]);
  plane->rays = std::move(kept);
}

LidarAxisOffsetResult solveLidarAxisOffset(const std::vector<LidarPlaneRays>& planes,
                                           const LidarAxisOffsetOptions& o) {
  if (planes.empty()) throw std::invalid_argument("lidar axis offset: no plane given");
  for (const auto& plane : planes) {
    if (plane.rays.size() < 3) {
      throw std::invalid_argument("lidar axis offset: " + plane.source + " has fewer than 3 rays");
    }
  }
  const auto t0 = Clock::now();
  LidarAxisOffsetResult r;
  r.y_estimated = o.estimate_y;
  LidarProblem p;
  buildProblem(planes, o, &p);
  r.cauchy_scale_mm = o.cauchy_scale_mm > 0 ? o.cauchy_scale_mm
                                            : 2.3849 * std::max(1e-6, robustSigma(residualsOf(p)));
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::SPARSE_SCHUR;  // planes eliminated, the offset left
  // Eigen's sparse Cholesky: SuiteSparse's runs OpenMP threads, whose sums may change from
  // run to run; the same logs must give the same bytes.
  so.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = 1e-12;
  so.parameter_tolerance = 1e-12;
  so.num_threads = 1;
  for (int pass = 0; pass < std::max(1, o.reweightings); ++pass) {
    setCauchyWeights(r.cauchy_scale_mm, &p);
    ceres::Solver::Summary summary;
    ceres::Solve(so, p.problem.get(), &summary);
    r.iterations += static_cast<int>(summary.iterations.size());
    r.converged = summary.termination_type == ceres::CONVERGENCE;
  }
  r.offset_mm = Eigen::Vector3d(p.t[0], p.t[1], p.t[2]);
  r.residuals = p.residuals;
  reportPlanes(planes, p, o, &r);
  flagUnobservable(analyse(p), o, r.walls, &r);
  standardDeviations(o, planes.size(), &p, &r);
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return r;
}

}  // namespace sweepmap
