// Mounting calibration of a 2D lidar on a moving base (Miao 2022 section 4.2, Eq. 15-17):
// the paper's point pairs with LM, and our point-to-plane Ceres refinement over every
// overlapping point of the two passes. See calib/mounting_calibration.hpp.
#include "calib/mounting_calibration.hpp"

#include <ceres/ceres.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "calib/overlap_alignment.hpp"
#include "calib/rotating_geometry.hpp"

namespace sweepmap {

const char* mountingMethodName(MountingMethod m) {
  switch (m) {
    case MountingMethod::kPaperPoints:
      return "paper_points";
    case MountingMethod::kPointToPlane:
      return "point_to_plane";
  }
  return "unknown";
}

namespace {

// One valid ray: its direction after the nominal rotation (q = R_nominal p_L), time, scan,
// and on which half of the scan it lies (+Y_L "left" or -Y_L "right").
struct Ray {
  Eigen::Vector3d q;
  int64_t utime;
  int scan;
  bool left;
  double range_m;
};

// The planar pose at (ray time + dt_lin) and its rate, so the pose at ray time + dt is
// pose + rate (dt - dt_lin): linear in dt around the current estimate, re-linearised each
// outer iteration (exact at convergence).
struct RayPose {
  double x, y, th, vx, vy, vth;
};

// Shared, read-only data of one solve.
struct Model {
  Eigen::Vector3d t_BL;
  double dt_lin = 0.0;
  double t_mid_us = 0.0;  // reference time of the track drift
};

template <typename T>
Eigen::Matrix<T, 3, 1> worldPoint(const Ray& ray, const RayPose& P, const Model& m, const T* ang,
                                  const T* dt, const T* drift = nullptr) {
  using std::cos;
  using std::sin;
  // R(g, b, a) q = Rz(a) Ry(b) Rx(g) q, as LidarMounting::T_BL.
  const T cg = cos(ang[0]), sg = sin(ang[0]);
  const T cb = cos(ang[1]), sb = sin(ang[1]);
  const T ca = cos(ang[2]), sa = sin(ang[2]);
  const T x1 = T(ray.q.x());
  const T y1 = cg * ray.q.y() - sg * ray.q.z();
  const T z1 = sg * ray.q.y() + cg * ray.q.z();
  const T x2 = cb * x1 + sb * z1;
  const T z2 = -sb * x1 + cb * z1;
  const T bx = ca * x2 - sa * y1 + m.t_BL.x();
  const T by = sa * x2 + ca * y1 + m.t_BL.y();
  const T bz = z2 + m.t_BL.z();
  const T ddt = dt[0] - m.dt_lin;
  const T px = P.x + P.vx * ddt;
  const T py = P.y + P.vy * ddt;
  const T th = P.th + P.vth * ddt;
  const T c = cos(th), s = sin(th);
  if (drift != nullptr) {
    // The track's slow position drift (odometry: its error grows at this world velocity),
    // taken off about the middle time.
    const T tt = T((double(ray.utime) - m.t_mid_us) * 1e-6);
    return {px + c * bx - s * by - drift[0] * tt, py + s * bx + c * by - drift[1] * tt, bz};
  }
  return {px + c * bx - s * by, py + s * bx + c * by, bz};
}

// Ours: the distance of point A from the local plane (normal n, fixed) through the
// centroid of its neighbours B in the other pass, all re-assembled with the parameters.
// Residual 1; parameters: (gamma, beta, alpha) [3], time offset [1], track drift [2].
struct PointToPlaneCost {
  PointToPlaneCost(const Model* m, Ray a, RayPose pa, std::vector<std::pair<Ray, RayPose>> b,
                   Eigen::Vector3d n, double weight)
      : m_(m), a_(a), pa_(pa), b_(std::move(b)), n_(n * weight) {}
  template <typename T>
  bool operator()(const T* ang, const T* dt, const T* drift, T* residual) const {
    Eigen::Matrix<T, 3, 1> c = Eigen::Matrix<T, 3, 1>::Zero();
    for (const auto& [ray, pose] : b_) c += worldPoint(ray, pose, *m_, ang, dt, drift);
    c /= T(double(b_.size()));
    const Eigen::Matrix<T, 3, 1> d = worldPoint(a_, pa_, *m_, ang, dt, drift) - c;
    residual[0] = n_.x() * d.x() + n_.y() * d.y() + n_.z() * d.z();
    return true;
  }
  static ceres::CostFunction* Create(const Model* m, const Ray& a, const RayPose& pa,
                                     std::vector<std::pair<Ray, RayPose>> b,
                                     const Eigen::Vector3d& n, double weight) {
    return new ceres::AutoDiffCostFunction<PointToPlaneCost, 1, 3, 1, 2>(
        new PointToPlaneCost(m, a, pa, std::move(b), n, weight));
  }
  const Model* m_;
  Ray a_;
  RayPose pa_;
  std::vector<std::pair<Ray, RayPose>> b_;
  Eigen::Vector3d n_;
};

// The paper's Eq. 15-17: the difference of a pair of corresponding points of the two
// passes. Residual 3; parameters: (gamma, beta, alpha) [3], time offset [1] (held constant).
struct PointPairCost {
  PointPairCost(const Model* m, Ray a, RayPose pa, Ray b, RayPose pb)
      : m_(m), a_(a), pa_(pa), b_(b), pb_(pb) {}
  template <typename T>
  bool operator()(const T* ang, const T* dt, T* residual) const {
    const Eigen::Matrix<T, 3, 1> d =
        worldPoint(a_, pa_, *m_, ang, dt) - worldPoint(b_, pb_, *m_, ang, dt);
    residual[0] = d.x();
    residual[1] = d.y();
    residual[2] = d.z();
    return true;
  }
  static ceres::CostFunction* Create(const Model* m, const Ray& a, const RayPose& pa, const Ray& b,
                                     const RayPose& pb) {
    return new ceres::AutoDiffCostFunction<PointPairCost, 3, 3, 1>(
        new PointPairCost(m, a, pa, b, pb));
  }
  const Model* m_;
  Ray a_;
  RayPose pa_;
  Ray b_;
  RayPose pb_;
};

std::optional<Pose2> poseAt(const PoseTrack& track, double t_us) {
  return track.at(static_cast<int64_t>(std::llround(t_us)));
}

// Poses (and rates) of every ray at ray time + dt; false where the track does not cover it.
void computePoses(const std::vector<Ray>& rays, const PoseTrack& track, double dt_s,
                  std::vector<RayPose>* poses, std::vector<char>* covered) {
  constexpr double kHalfStepUs = 10'000.0;  // central difference over 20 ms
  poses->assign(rays.size(), RayPose{});
  covered->assign(rays.size(), 0);
  for (size_t i = 0; i < rays.size(); ++i) {
    const double t = double(rays[i].utime) + dt_s * 1e6;
    const auto p = poseAt(track, t);
    if (!p) continue;
    auto lo = poseAt(track, t - kHalfStepUs);
    auto hi = poseAt(track, t + kHalfStepUs);
    double span_us = 2 * kHalfStepUs;
    if (!lo) {
      lo = p;
      span_us -= kHalfStepUs;
    }
    if (!hi) {
      hi = p;
      span_us -= kHalfStepUs;
    }
    RayPose& r = (*poses)[i];
    r.x = p->x_m;
    r.y = p->y_m;
    r.th = p->theta_rad;
    if (span_us > 0) {
      const double s = span_us * 1e-6;
      r.vx = (hi->x_m - lo->x_m) / s;
      r.vy = (hi->y_m - lo->y_m) / s;
      r.vth = wrapAngle(hi->theta_rad - lo->theta_rad) / s;
    }
    (*covered)[i] = 1;
  }
}

struct Prepared {
  std::vector<Ray> rays;
  std::vector<int> scan_first;  // index of each scan's first ray in `rays`
};

Prepared prepare(const std::vector<Scan2D>& scans, const LidarMounting& initial, int stride) {
  Prepared p;
  const Eigen::Matrix3d R_nom = rotationXYZ(
      initial.nominal_rpy_rad.x(), initial.nominal_rpy_rad.y(), initial.nominal_rpy_rad.z());
  for (size_t s = 0; s < scans.size(); ++s) {
    const Scan2D& scan = scans[s];
    for (size_t i = 0; i < scan.ranges_m.size(); i += size_t(stride)) {
      if (!scan.validRange(i)) continue;
      const double r = scan.ranges_m[i];
      const double a = scan.rayAngle(i);
      p.rays.push_back(
          {R_nom * rotating::pointInLidar(r, a), scan.rayUtime(i), int(s), std::sin(a) > 0.0, r});
    }
  }
  return p;
}

// Rays whose pose is known, re-assembled into the world with the current estimate.
struct WorldCloud {
  std::vector<int> ray;  // index into rays
  std::vector<Eigen::Vector3d> p;
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud{new pcl::PointCloud<pcl::PointXYZ>};
  pcl::KdTreeFLANN<pcl::PointXYZ> tree{false};  // unsorted off below: we sort ourselves
};

void buildWorld(const std::vector<Ray>& rays, const std::vector<RayPose>& poses,
                const std::vector<char>& covered, const std::vector<int>& which, const Model& m,
                const double* ang, double dt, WorldCloud* w, const double* drift = nullptr) {
  w->ray.clear();
  w->p.clear();
  w->cloud->clear();
  for (int i : which) {
    if (!covered[i]) continue;
    const Eigen::Vector3d p = worldPoint(rays[i], poses[i], m, ang, &dt, drift);
    w->ray.push_back(i);
    w->p.push_back(p);
    w->cloud->push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
  }
  if (!w->cloud->empty()) w->tree.setInputCloud(w->cloud);
}

// Indices (into w) within radius of p, in the k-d tree's order (deterministic for the same
// cloud).
std::vector<int> neighboursUnsorted(const WorldCloud& w, const Eigen::Vector3d& p, double radius) {
  std::vector<int> idx;
  std::vector<float> d2;
  w.tree.radiusSearch(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())), radius, idx, d2);
  return idx;
}

// Indices (into w) within radius of p, nearest first (ties by index: deterministic; the
// order depends only on which points are within the radius).
std::vector<int> neighbours(const WorldCloud& w, const Eigen::Vector3d& p, double radius) {
  std::vector<int> idx = neighboursUnsorted(w, p, radius);
  std::vector<std::pair<double, int>> order;
  order.reserve(idx.size());
  for (int k : idx) order.emplace_back((w.p[k] - p).squaredNorm(), k);
  std::sort(order.begin(), order.end());
  idx.clear();
  for (const auto& o : order) idx.push_back(o.second);
  return idx;
}

bool otherPass(const Ray& a, const Ray& b, const MountingCalibrationOptions& o) {
  if (o.opposite_sides_only && a.left == b.left) return false;
  return std::abs(double(a.utime - b.utime)) >= o.min_pass_gap_s * 1e6;
}

void configureSolver(ceres::Solver::Options* so, int max_iterations) {
  so->linear_solver_type = ceres::DENSE_QR;
  so->trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so->max_num_iterations = max_iterations;
  so->function_tolerance = 1e-14;
  so->gradient_tolerance = 1e-16;
  so->parameter_tolerance = 1e-14;
  so->num_threads = 1;  // deterministic sums
  so->logging_type = ceres::SILENT;
  so->minimizer_progress_to_stdout = false;
}

// Least-squares plane (PCA) of `pts` (calib/overlap_alignment.hpp's fitPcaPlane).
bool fitPlane(const std::vector<Eigen::Vector3d>& pts, double max_ratio, double max_variance,
              Eigen::Vector3d* mean, Eigen::Vector3d* normal) {
  return fitPcaPlane(pts.data(), static_cast<int>(pts.size()), max_ratio, max_variance, mean,
                     normal);
}

// One outer iteration of either method: the rays, their poses and the world cloud
// re-assembled with the current estimate, whose parameter blocks (ang[3], dt and, for
// ours, drift[2]; else nullptr) the residual blocks refine.
struct Round {
  const std::vector<Ray>& rays;
  const std::vector<RayPose>& poses;
  const WorldCloud& w;
  const Model& model;
  double* ang;
  double* dt;
  double* drift;
};

// ---------------------------------------------------------------------------------------
// Ours: point-to-plane over all overlapping points.

// The neighbours of query k within plane_radius_m: of the other pass (the local plane),
// and of the query's own pass (same half of the scan, less than min_pass_gap_s away: the
// plane the query itself lies on).
struct Patch {
  std::vector<Eigen::Vector3d> others, own;
  std::vector<int> other_idx;  // of the other pass within the plane radius (into w)
  double range_sum = 0.0;      // of the query and the other pass's points
};

// One query point's residual block: its distance from the other pass's local plane.
struct PlaneResidual {
  std::vector<std::pair<Ray, RayPose>> nb;  // the other pass's nearest points in the plane
  Eigen::Vector3d n;                        // the plane's normal (held fixed in the cost)
  double r = 0.0;                           // the residual at the current estimate [m]
  double weight = 1.0, loss_scale = 0.0;
};

// The residuals of one outer iteration, in the order of their residual blocks.
struct RoundResiduals {
  std::vector<double> r0;       // residuals at the current estimate [m]
  std::vector<double> weights;  // of each residual block (1 / its sigma, or 1)
  int pairs = 0;
};

// The other pass's neighbours make the local plane; the query's own pass's neighbours
// must see a plane with the same normal there (the query is on that surface, not on
// another one near an edge: such one-sided residuals would bias the estimate).
Patch gatherPatch(const Round& rd, size_t k, const MountingCalibrationOptions& o) {
  const Ray& a = rd.rays[rd.w.ray[k]];
  Patch patch;
  patch.range_sum = a.range_m;
  for (int j : neighboursUnsorted(rd.w, rd.w.p[k], o.plane_radius_m)) {
    const Ray& b = rd.rays[rd.w.ray[j]];
    if (otherPass(a, b, o)) {
      patch.other_idx.push_back(j);
      patch.others.push_back(rd.w.p[j]);
      patch.range_sum += b.range_m;
    } else if (o.check_own_plane && b.left == a.left &&
               std::abs(double(b.utime - a.utime)) < o.min_pass_gap_s * 1e6) {
      patch.own.push_back(rd.w.p[j]);
    }
  }
  return patch;
}

// The residual's neighbours: the other pass's points nearest to the query within the
// plane (distance along the normal ignored: that is where the range noise lies, and
// choosing by it would pick the neighbours whose noise agrees with the query's), up to
// max_neighbours. False if fewer than min_neighbours are within neighbour_radius_m.
bool nearestInPlane(const Round& rd, size_t k, const std::vector<int>& other_idx,
                    const Eigen::Vector3d& n, const MountingCalibrationOptions& o,
                    std::vector<std::pair<Ray, RayPose>>* nb) {
  std::vector<std::pair<double, int>> order;
  for (int j : other_idx) {
    const Eigen::Vector3d off = rd.w.p[j] - rd.w.p[k];
    const double d2 = (off - n * n.dot(off)).squaredNorm();
    if (d2 <= o.neighbour_radius_m * o.neighbour_radius_m) order.emplace_back(d2, j);
  }
  if (int(order.size()) < o.min_neighbours) return false;
  const size_t count = std::min(order.size(), size_t(o.max_neighbours));
  std::partial_sort(order.begin(), order.begin() + std::ptrdiff_t(count), order.end());
  for (size_t i = 0; i < count; ++i) {
    const int j = rd.w.ray[order[i].second];
    nb->emplace_back(rd.rays[j], rd.poses[j]);
  }
  return true;
}

// The direction of a ray in the world, with the current estimate.
Eigen::Vector3d rayDirection(const Round& rd, const Ray& ray, const RayPose& pose) {
  const Ray origin{Eigen::Vector3d::Zero(), ray.utime, ray.scan, ray.left, 0.0};
  return (worldPoint(ray, pose, rd.model, rd.ang, rd.dt, rd.drift) -
          worldPoint(origin, pose, rd.model, rd.ang, rd.dt, rd.drift))
      .normalized();
}

// The residual's weight and the Cauchy loss's scale: the residual in sigmas of its
// predicted noise (the query's range noise along the normal, the mean of its neighbours',
// and the model's floor) with noise_weighting; else metres and loss_scale_m.
void weigh(const Round& rd, const Ray& a, const RayPose& pose_a,
           const MountingCalibrationOptions& o, PlaneResidual* pr) {
  pr->weight = 1.0;
  pr->loss_scale = o.loss_scale_m;
  if (!o.noise_weighting) return;
  // Near points are up to ten times more precise than far ones (the X4's noise grows with
  // range).
  const auto variance = [&](const Ray& ray, const RayPose& pose) {
    const double s = o.range_noise_fraction * ray.range_m * rayDirection(rd, ray, pose).dot(pr->n);
    return s * s;
  };
  double var_nb = 0.0;
  for (const auto& [b, pb] : pr->nb) var_nb += variance(b, pb);
  var_nb /= double(pr->nb.size() * pr->nb.size());
  pr->weight = 1.0 / std::sqrt(variance(a, pose_a) + var_nb + o.model_sigma_m * o.model_sigma_m);
  // Not tighter than loss_scale_m: the first rounds start centimetres out of alignment.
  pr->loss_scale = std::max(o.loss_scale_sigmas, o.loss_scale_m * pr->weight);
}

// Query k's residual against the other pass's local plane, unless the patch there is not
// flat, not seen as the same plane by the query's own pass, grazing, or the query lies
// beyond its rim or (after the first round, `trim`) too far from it.
std::optional<PlaneResidual> planeResidual(const Round& rd, size_t k, bool trim,
                                           double robust_trim_m,
                                           const MountingCalibrationOptions& o) {
  const Ray& a = rd.rays[rd.w.ray[k]];
  const Patch patch = gatherPatch(rd, k, o);
  if (int(patch.others.size()) < o.min_neighbours) return std::nullopt;
  // A plane is flat to within the range noise (sigma = range_noise_fraction * range,
  // at most along the normal) plus a millimetre: edges and corners are rejected.
  const double sigma = o.range_noise_fraction * patch.range_sum / double(patch.others.size() + 1);
  const double max_var = 2.0 * sigma * sigma + 1e-6;
  PlaneResidual pr;
  Eigen::Vector3d mean;
  if (!fitPlane(patch.others, o.max_planarity_ratio, max_var, &mean, &pr.n)) return std::nullopt;
  const Eigen::Vector3d& n = pr.n;
  if (!nearestInPlane(rd, k, patch.other_idx, n, o, &pr.nb)) return std::nullopt;
  if (o.check_own_plane) {
    Eigen::Vector3d own_mean, own_n;
    if (int(patch.own.size()) < o.min_neighbours) return std::nullopt;
    if (!fitPlane(patch.own, o.max_planarity_ratio, max_var, &own_mean, &own_n))
      return std::nullopt;
    if (std::abs(own_n.dot(n)) < std::cos(o.max_normal_angle_rad)) return std::nullopt;
  }
  // The residual's plane: through the centroid of the nearest neighbours of the other
  // pass (re-assembled in the cost), with the patch's normal.
  mean.setZero();
  for (const auto& [b, pb] : pr.nb) mean += worldPoint(b, pb, rd.model, rd.ang, rd.dt, rd.drift);
  mean /= double(pr.nb.size());
  const RayPose& pose_a = rd.poses[rd.w.ray[k]];
  if (o.max_incidence_rad < 0.5 * M_PI) {
    // Grazing rays: the range noise lies mostly in the plane and the patch is stretched
    // along the ray; such patches are skipped for the query's and the neighbours' rays.
    const double c = std::cos(o.max_incidence_rad);
    if (std::abs(rayDirection(rd, a, pose_a).dot(n)) < c ||
        std::abs(rayDirection(rd, pr.nb.front().first, pr.nb.front().second).dot(n)) < c) {
      return std::nullopt;
    }
  }
  // The query lies over the middle of the patch, not beyond its rim.
  const Eigen::Vector3d off = rd.w.p[k] - mean;
  if ((off - n * n.dot(off)).norm() > 0.5 * o.neighbour_radius_m) return std::nullopt;
  pr.r = n.dot(rd.w.p[k] - mean);
  // After the first round, residuals beyond what the range noise explains are dropped
  // (points over an edge of the other pass's surface). The bound comes from the noise
  // model, not from the residuals at the current estimate: trimming by those reinforces
  // the estimate and, with noise, made it drift (0.2 mrad per outer iteration in alpha
  // on the simulated circle).
  double trim_m = std::max(o.min_trim_m, o.trim_noise_sigmas * sigma);
  if (o.trim_sigmas > 0) trim_m = std::min(trim_m, std::max(o.min_trim_m, robust_trim_m));
  if (trim && std::abs(pr.r) > trim_m) return std::nullopt;
  weigh(rd, a, pose_a, o, &pr);
  return pr;
}

// Every query_stride-th point within the query ranges that has a plane residual: its
// residual block in `problem`.
RoundResiduals addPlaneResiduals(const Round& rd, bool trim, double robust_trim_m,
                                 const MountingCalibrationOptions& o, ceres::Problem* problem) {
  RoundResiduals rs;
  for (size_t k = 0; k < rd.w.p.size(); k += size_t(o.query_stride)) {
    const Ray& a = rd.rays[rd.w.ray[k]];
    if (a.range_m < o.min_range_m || a.range_m > o.max_range_m) continue;
    std::optional<PlaneResidual> pr = planeResidual(rd, k, trim, robust_trim_m, o);
    if (!pr) continue;
    rs.r0.push_back(pr->r);
    rs.weights.push_back(pr->weight);
    const RayPose& pose_a = rd.poses[rd.w.ray[k]];
    problem->AddResidualBlock(
        PointToPlaneCost::Create(&rd.model, a, pose_a, std::move(pr->nb), pr->n, pr->weight),
        new ceres::CauchyLoss(pr->loss_scale), rd.ang, rd.dt, rd.drift);
    ++rs.pairs;
  }
  return rs;
}

// trim_sigmas robust sigmas (1.4826 median absolute residual) of the round's residuals.
double robustTrim(const std::vector<double>& r0, const MountingCalibrationOptions& o) {
  std::vector<double> absr;
  for (double r : r0) absr.push_back(std::abs(r));
  std::nth_element(absr.begin(), absr.begin() + absr.size() / 2, absr.end());
  return o.trim_sigmas * 1.4826 * absr[absr.size() / 2];
}

// RMS of the plain residuals (no loss, no weights) at the problem's current parameters.
double plainRms(ceres::Problem* problem, const std::vector<double>& weights) {
  std::vector<double> rr;
  ceres::Problem::EvaluateOptions eo;
  eo.apply_loss_function = false;
  double cost = 0.0;
  problem->Evaluate(eo, &cost, &rr, nullptr, nullptr);
  double s2 = 0.0;
  for (size_t i = 0; i < rr.size(); ++i) s2 += (rr[i] / weights[i]) * (rr[i] / weights[i]);
  return std::sqrt(s2 / double(rr.size()));
}

MountingCalibrationResult pointToPlane(const Prepared& prep, const PoseTrack& track,
                                       const LidarMounting& initial,
                                       const MountingCalibrationOptions& o) {
  MountingCalibrationResult res;
  res.method = MountingMethod::kPointToPlane;
  const std::vector<Ray>& rays = prep.rays;
  Model model;
  model.t_BL = initial.t_BL_m;
  double ang[3] = {initial.gamma_rad, initial.beta_rad, initial.alpha_rad};
  double dt = o.estimate_time_offset ? o.initial_time_offset_s : 0.0;
  double drift[2] = {0.0, 0.0};
  const bool with_drift = o.estimate_track_drift;
  if (!rays.empty())
    model.t_mid_us = 0.5 * (double(rays.front().utime) + double(rays.back().utime));

  std::vector<int> all(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) all[i] = int(i);
  std::vector<RayPose> poses;
  std::vector<char> covered;
  bool first = true;
  double robust_trim_m = o.neighbour_radius_m;  // trim_sigmas robust sigmas of the last round
  for (int outer = 0; outer < o.max_outer_iterations; ++outer) {
    model.dt_lin = dt;
    computePoses(rays, track, dt, &poses, &covered);
    WorldCloud w;
    buildWorld(rays, poses, covered, all, model, ang, dt, &w, drift);
    if (w.p.size() < 100) {
      res.reason = "the pose track covers too few lidar rays (" + std::to_string(w.p.size()) + ")";
      return res;
    }

    ceres::Problem problem;
    const Round rd{rays, poses, w, model, ang, &dt, drift};
    const RoundResiduals rs = addPlaneResiduals(rd, !first, robust_trim_m, o, &problem);
    if (rs.pairs < o.min_correspondences) {
      res.reason = "too few overlapping points of the two passes (" + std::to_string(rs.pairs) +
                   " < " + std::to_string(o.min_correspondences) + ")";
      return res;
    }
    if (o.trim_sigmas > 0) robust_trim_m = robustTrim(rs.r0, o);
    double ss = 0.0;
    for (double r : rs.r0) ss += r * r;
    const double rms0 = std::sqrt(ss / double(rs.r0.size()));
    if (first) res.residual_before_m = rms0;
    first = false;

    if (o.estimate_time_offset) {
      problem.SetParameterLowerBound(&dt, 0, -o.max_time_offset_s);
      problem.SetParameterUpperBound(&dt, 0, o.max_time_offset_s);
    } else {
      problem.SetParameterBlockConstant(&dt);
    }
    if (!with_drift) problem.SetParameterBlockConstant(drift);
    const double before[4] = {ang[0], ang[1], ang[2], dt};
    ceres::Solver::Options so;
    configureSolver(&so, o.max_solver_iterations);
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    res.iterations += int(summary.iterations.size());
    res.correspondences = rs.pairs;
    res.residual_after_m = plainRms(&problem, rs.weights);  // with this round's correspondences
    const double change = std::max({std::abs(ang[0] - before[0]), std::abs(ang[1] - before[1]),
                                    std::abs(ang[2] - before[2]), std::abs(dt - before[3]) * 1e-2});
    if (outer >= 1 && change < o.convergence_rad) break;
  }
  res.gamma_rad = ang[0];
  res.beta_rad = ang[1];
  res.alpha_rad = ang[2];
  res.time_offset_s = o.estimate_time_offset ? dt : 0.0;
  res.drift_x_m_s = drift[0];
  res.drift_y_m_s = drift[1];
  res.ok = true;
  return res;
}

// ---------------------------------------------------------------------------------------
// The paper's: corresponding edge points of the two passes (automatic: range
// discontinuities, where a nearer surface such as the target board ends in front of a
// farther one), Levenberg-Marquardt on the sum of squared distances (Eq. 15-17).

// The target's edge points in scan `s`: a run of rays without range jumps (the board)
// with a jump to something farther at both ends (the window recess behind it) and the
// board's extent between its end points. Each end is an edge point, placed half an angle
// step beyond the run's last ray at its range: no bias from the ray spacing on average.
void addTargetEdges(const Scan2D& scan, int s, const Eigen::Matrix3d& R_nom,
                    const MountingCalibrationOptions& o, std::vector<Ray>* rays) {
  const size_t n = scan.ranges_m.size();
  const auto edge = [&](size_t inner, size_t outer) {
    const double r = scan.ranges_m[inner];
    const double a = 0.5 * (scan.rayAngle(inner) + scan.rayAngle(outer));
    return Ray{R_nom * rotating::pointInLidar(r, a), scan.rayUtime(inner), s, std::sin(a) > 0.0, r};
  };
  size_t i = 1;
  while (i + 1 < n) {
    if (!scan.validRange(i) || !scan.validRange(i - 1) ||
        scan.ranges_m[i - 1] < scan.ranges_m[i] + o.edge_jump_m) {
      ++i;
      continue;
    }
    size_t j = i;  // the run [i, j]
    while (j + 1 < n && scan.validRange(j + 1) &&
           std::abs(scan.ranges_m[j + 1] - scan.ranges_m[j]) < o.edge_jump_m)
      ++j;
    const bool closed = j + 1 < n && scan.validRange(j + 1) &&
                        scan.ranges_m[j + 1] > scan.ranges_m[j] + o.edge_jump_m;
    const double r_i = scan.ranges_m[i], r_j = scan.ranges_m[j];
    const double extent = (rotating::pointInLidar(r_i, scan.rayAngle(i)) -
                           rotating::pointInLidar(r_j, scan.rayAngle(j)))
                              .norm();
    if (closed && j >= i + 2 && extent >= o.target_min_extent_m &&
        extent <= o.target_max_extent_m && std::min(r_i, r_j) >= o.min_range_m &&
        std::max(r_i, r_j) <= o.max_edge_range_m) {
      rays->push_back(edge(i, i - 1));
      rays->push_back(edge(j, j + 1));
    }
    i = j + 1;
  }
}

// Mutual nearest edge points of the two passes within match_m, each pair once (A on the
// left half): their residual blocks in `problem`. Returns the number of pairs and adds
// their squared distances at the current estimate to *ss.
int addEdgePairs(const Round& rd, double match_m, const MountingCalibrationOptions& o,
                 ceres::Problem* problem, double* ss) {
  const WorldCloud& w = rd.w;
  const auto nearestOther = [&](int k) {
    for (int j : neighbours(w, w.p[k], match_m)) {
      if (otherPass(rd.rays[w.ray[k]], rd.rays[w.ray[j]], o)) return j;
    }
    return -1;
  };
  int pairs = 0;
  for (size_t k = 0; k < w.p.size(); ++k) {
    if (!rd.rays[w.ray[k]].left && o.opposite_sides_only) continue;
    const int j = nearestOther(int(k));
    if (j < 0 || nearestOther(j) != int(k)) continue;
    if (!o.opposite_sides_only && j < int(k)) continue;
    *ss += (w.p[k] - w.p[j]).squaredNorm();
    problem->AddResidualBlock(
        PointPairCost::Create(&rd.model, rd.rays[w.ray[k]], rd.poses[w.ray[k]], rd.rays[w.ray[j]],
                              rd.poses[w.ray[j]]),
        nullptr, rd.ang, rd.dt);
    ++pairs;
  }
  return pairs;
}

MountingCalibrationResult paperPoints(const std::vector<Scan2D>& scans, const PoseTrack& track,
                                      const LidarMounting& initial,
                                      const MountingCalibrationOptions& o) {
  MountingCalibrationResult res;
  res.method = MountingMethod::kPaperPoints;
  const Eigen::Matrix3d R_nom = rotationXYZ(
      initial.nominal_rpy_rad.x(), initial.nominal_rpy_rad.y(), initial.nominal_rpy_rad.z());
  std::vector<Ray> rays;
  for (size_t s = 0; s < scans.size(); ++s) addTargetEdges(scans[s], int(s), R_nom, o, &rays);
  Model model;
  model.t_BL = initial.t_BL_m;
  double ang[3] = {initial.gamma_rad, initial.beta_rad, initial.alpha_rad};
  double dt = 0.0;
  std::vector<RayPose> poses;
  std::vector<char> covered;
  computePoses(rays, track, dt, &poses, &covered);
  std::vector<int> all(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) all[i] = int(i);

  double match_m = o.edge_match_m;
  for (int outer = 0; outer < o.max_outer_iterations; ++outer) {
    WorldCloud w;
    buildWorld(rays, poses, covered, all, model, ang, dt, &w);
    if (w.p.size() < 2) break;
    ceres::Problem problem;
    double ss = 0.0;
    const int pairs =
        addEdgePairs({rays, poses, w, model, ang, &dt, nullptr}, match_m, o, &problem, &ss);
    if (pairs < o.min_point_pairs) {
      res.reason = "too few corresponding edge points of the two passes (" + std::to_string(pairs) +
                   " < " + std::to_string(o.min_point_pairs) + ")";
      return res;
    }
    if (outer == 0) res.residual_before_m = std::sqrt(ss / pairs);
    problem.SetParameterBlockConstant(&dt);
    const double before[3] = {ang[0], ang[1], ang[2]};
    ceres::Solver::Options so;
    configureSolver(&so, o.max_solver_iterations);
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    res.iterations += int(summary.iterations.size());
    res.correspondences = pairs;
    res.residual_after_m = std::sqrt(2.0 * summary.final_cost / pairs);
    match_m = std::max(o.edge_match_min_m, 0.5 * match_m);
    const double change = std::max(
        {std::abs(ang[0] - before[0]), std::abs(ang[1] - before[1]), std::abs(ang[2] - before[2])});
    if (outer >= 1 && change < o.convergence_rad && match_m <= o.edge_match_min_m) break;
  }
  if (res.correspondences == 0) {
    res.reason = "no edge points (range discontinuities) seen by both passes";
    return res;
  }
  res.gamma_rad = ang[0];
  res.beta_rad = ang[1];
  res.alpha_rad = ang[2];
  res.ok = true;
  return res;
}

// Ours with the fast engine (calib/overlap_alignment.hpp): the same residuals, the mounting
// angles and, as asked, the time offset and the track drift; the lever arm held.
MountingCalibrationResult fastPointToPlane(const std::vector<Scan2D>& scans, const PoseTrack& track,
                                           const LidarMounting& initial,
                                           const MountingCalibrationOptions& o) {
  using M = MobileOverlapModel;
  const std::vector<OverlapRay> rays = overlapRays(scans, initial.nominal_rpy_rad, o);
  M model(rays, track, initial.t_BL_m);
  OverlapOptions oo;
  oo.base = o;
  oo.threads = o.threads;
  oo.progress = o.progress;
  const int P = model.parameterCount();
  oo.free.assign(size_t(P), false);
  for (int k : {M::kGamma, M::kBeta, M::kAlpha}) oo.free[size_t(k)] = true;
  oo.free[M::kTimeOffset] = o.estimate_time_offset;
  oo.free[M::kDriftX] = oo.free[M::kDriftY] = o.estimate_track_drift;
  oo.lower = Eigen::VectorXd::Constant(P, -1e300);
  oo.upper = Eigen::VectorXd::Constant(P, 1e300);
  oo.lower(M::kTimeOffset) = -o.max_time_offset_s;
  oo.upper(M::kTimeOffset) = o.max_time_offset_s;
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(P);
  x0(M::kGamma) = initial.gamma_rad;
  x0(M::kBeta) = initial.beta_rad;
  x0(M::kAlpha) = initial.alpha_rad;
  if (o.estimate_time_offset) x0(M::kTimeOffset) = o.initial_time_offset_s;
  const OverlapResult r = alignOverlap(rays, model, x0, oo);
  MountingCalibrationResult res;
  res.method = MountingMethod::kPointToPlane;
  res.ok = r.ok;
  res.reason = r.reason;
  if (!r.ok) return res;
  res.gamma_rad = r.x(M::kGamma);
  res.beta_rad = r.x(M::kBeta);
  res.alpha_rad = r.x(M::kAlpha);
  res.time_offset_s = o.estimate_time_offset ? r.x(M::kTimeOffset) : 0.0;
  res.drift_x_m_s = r.x(M::kDriftX);
  res.drift_y_m_s = r.x(M::kDriftY);
  res.sigma_gamma_rad = std::sqrt(r.covariance(M::kGamma, M::kGamma));
  res.sigma_beta_rad = std::sqrt(r.covariance(M::kBeta, M::kBeta));
  res.sigma_alpha_rad = std::sqrt(r.covariance(M::kAlpha, M::kAlpha));
  res.sigma_time_offset_s = std::sqrt(r.covariance(M::kTimeOffset, M::kTimeOffset));
  res.residual_before_m = r.residual_before_m;
  res.residual_after_m = r.residual_after_m;
  res.correspondences = r.correspondences;
  res.iterations = r.rounds;
  return res;
}

}  // namespace

MountingCalibrationResult calibrateMounting(const std::vector<Scan2D>& scans,
                                            const PoseTrack& track, const LidarMounting& initial,
                                            const MountingCalibrationOptions& options) {
  MountingCalibrationResult fail;
  fail.method = options.method;
  if (scans.size() < 2 || track.size() < 2) {
    fail.reason = "too little data: " + std::to_string(scans.size()) + " scans, " +
                  std::to_string(track.size()) + " poses";
    return fail;
  }
  const int64_t span_us = scans.back().utime - scans.front().utime;
  if (double(span_us) < options.min_pass_gap_s * 1e6) {
    fail.reason = "the scans span " + std::to_string(span_us * 1e-6) +
                  " s, less than min_pass_gap_s: no second pass";
    return fail;
  }
  if (options.method == MountingMethod::kPaperPoints)
    return paperPoints(scans, track, initial, options);
  if (!options.reference_solver) return fastPointToPlane(scans, track, initial, options);
  const Prepared prep = prepare(scans, initial, std::max(1, options.ray_stride));
  return pointToPlane(prep, track, initial, options);
}

}  // namespace sweepmap
