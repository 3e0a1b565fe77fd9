#include "calib/walls.hpp"

#include <pcl/ModelCoefficients.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>

#include "core/angles.hpp"

namespace sweepmap {
namespace {

// Orients a plane so that its normal points toward the origin (offset > 0).
void orientTowardOrigin(WallPlaneFit* w) {
  if (w->offset < 0) {
    w->normal = -w->normal;
    w->offset = -w->offset;
  }
}

std::vector<int> pointsNear(const std::vector<Eigen::Vector3f>& cloud, const Eigen::Vector3d& n,
                            double offset, double distance_m) {
  std::vector<int> idx;
  const Eigen::Vector3f nf = n.cast<float>();
  const float d = static_cast<float>(offset);
  const float t = static_cast<float>(distance_m);
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (std::abs(nf.dot(cloud[i]) + d) <= t) idx.push_back(static_cast<int>(i));
  }
  return idx;
}

// Removes the points of horizontal slabs (floor, ceiling): z-slices holding more than
// `factor` times the median slice count.
pcl::PointCloud<pcl::PointXYZ>::Ptr withoutHorizontalSlabs(const pcl::PointCloud<pcl::PointXYZ>& in,
                                                           double slice_m, double factor) {
  auto out = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  if (factor <= 0 || in.empty()) {
    *out = in;
    return out;
  }
  std::map<long, int> counts;
  const auto slice = [&](float z) { return static_cast<long>(std::floor(z / slice_m)); };
  for (const auto& p : in) ++counts[slice(p.z)];
  std::vector<int> c;
  for (const auto& [k, n] : counts) c.push_back(n);
  std::nth_element(c.begin(), c.begin() + c.size() / 2, c.end());
  const double limit = factor * c[c.size() / 2];
  out->reserve(in.size());
  for (const auto& p : in) {
    if (counts[slice(p.z)] <= limit) out->push_back(p);
  }
  return out;
}

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
}

}  // namespace

bool fitPlaneLeastSquares(const std::vector<Eigen::Vector3f>& cloud, const std::vector<int>& idx,
                          Eigen::Vector3d* normal, double* offset) {
  if (idx.size() < 3) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : idx) mean += cloud[i].cast<double>();
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : idx) {
    const Eigen::Vector3d d = cloud[i].cast<double>() - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  if (es.info() != Eigen::Success) return false;
  *normal = es.eigenvectors().col(0).normalized();
  *offset = -normal->dot(mean);
  return true;
}

std::vector<WallPlaneFit> refitWalls(const std::vector<Eigen::Vector3f>& cloud,
                                     const std::vector<WallPlaneFit>& walls, double distance_m) {
  std::vector<WallPlaneFit> out;
  for (const WallPlaneFit& w : walls) {
    WallPlaneFit r;
    r.normal = w.normal;
    r.offset = w.offset;
    Eigen::Vector3d n;
    double d = 0;
    if (fitPlaneLeastSquares(cloud, pointsNear(cloud, w.normal, w.offset, distance_m), &n, &d)) {
      if (n.dot(w.normal) < 0) {
        n = -n;
        d = -d;
      }
      r.normal = n;
      r.offset = d;
      r.inlier_indices = pointsNear(cloud, n, d, distance_m);
      r.inliers = static_cast<int>(r.inlier_indices.size());
      double ss = 0;
      for (int i : r.inlier_indices) {
        const double e = n.dot(cloud[i].cast<double>()) + d;
        ss += e * e;
      }
      r.rms_m = r.inliers > 0 ? std::sqrt(ss / r.inliers) : 0.0;
    }
    out.push_back(std::move(r));
  }
  return out;
}

namespace {

pcl::PointCloud<pcl::PointXYZ>::Ptr downsampled(const std::vector<Eigen::Vector3f>& cloud,
                                                double voxel_m) {
  auto full = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  full->reserve(cloud.size());
  for (const auto& p : cloud) {
    if (p.allFinite()) full->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  if (voxel_m <= 0) return full;
  auto down = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(full);
  const float v = static_cast<float>(voxel_m);
  grid.setLeafSize(v, v, v);
  grid.filter(*down);
  return down;
}

// Up to `max_planes` RANSAC planes of `model` (PLANE, or PARALLEL_/PERPENDICULAR_PLANE to
// Z within `eps_angle_rad`), largest first, each removed before the next; oriented toward
// the origin. Stops at the first plane with fewer than `min_inliers` points.
std::vector<WallPlaneFit> ransacPlanes(pcl::PointCloud<pcl::PointXYZ>::Ptr remaining,
                                       pcl::SacModel model, double eps_angle_rad, double distance_m,
                                       int max_planes, int min_inliers, int max_iterations) {
  std::vector<WallPlaneFit> planes;
  pcl::SACSegmentation<pcl::PointXYZ> seg;
  seg.setOptimizeCoefficients(true);
  seg.setModelType(model);
  seg.setMethodType(pcl::SAC_RANSAC);
  // One thread: PCL's default (-1) runs RANSAC's samples in OpenMP threads, and which
  // sample wins then depends on the scheduler: results changed under load.
  seg.setNumberOfThreads(1);
  seg.setAxis(Eigen::Vector3f::UnitZ());
  seg.setEpsAngle(eps_angle_rad);
  seg.setDistanceThreshold(distance_m);
  seg.setMaxIterations(max_iterations);
  for (int k = 0; k < max_planes; ++k) {
    if (static_cast<int>(remaining->size()) < std::max(min_inliers, 3)) break;
    pcl::ModelCoefficients coeff;
    pcl::PointIndices inliers;
    seg.setInputCloud(remaining);
    seg.segment(inliers, coeff);
    if (static_cast<int>(inliers.indices.size()) < min_inliers || coeff.values.size() != 4) break;
    WallPlaneFit w;
    w.normal = Eigen::Vector3d(coeff.values[0], coeff.values[1], coeff.values[2]);
    const double norm = w.normal.norm();
    w.normal /= norm;
    w.offset = coeff.values[3] / norm;
    w.inliers = static_cast<int>(inliers.indices.size());
    orientTowardOrigin(&w);
    planes.push_back(w);
    // Remove the plane's points and look for the next one.
    std::vector<char> drop(remaining->size(), 0);
    for (int i : inliers.indices) drop[i] = 1;
    auto next = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    next->reserve(remaining->size() - inliers.indices.size());
    for (size_t i = 0; i < remaining->size(); ++i) {
      if (!drop[i]) next->push_back((*remaining)[i]);
    }
    remaining = next;
  }
  return planes;
}

}  // namespace

std::vector<WallPlaneFit> extractPlanes(const std::vector<Eigen::Vector3f>& cloud,
                                        const PlaneExtractionOptions& options) {
  using O = PlaneExtractionOptions::Orientation;
  // PARALLEL_PLANE: parallel to the axis (vertical walls); PERPENDICULAR_PLANE: normal
  // along the axis (floors, ceilings).
  const pcl::SacModel model = options.orientation == O::kAny ? pcl::SACMODEL_PLANE
                              : options.orientation == O::kVertical
                                  ? pcl::SACMODEL_PARALLEL_PLANE
                                  : pcl::SACMODEL_PERPENDICULAR_PLANE;
  std::vector<WallPlaneFit> planes =
      ransacPlanes(downsampled(cloud, options.voxel_m), model, options.max_tilt_deg * kDegToRad,
                   options.distance_threshold_m, options.max_planes, options.min_inliers,
                   options.ransac_max_iterations);
  std::vector<WallPlaneFit> out;
  for (const WallPlaneFit& p : refitWalls(cloud, planes, options.distance_threshold_m)) {
    if (p.inliers >= 3) out.push_back(p);
  }
  return out;
}

namespace {

// Two facing walls: candidates a and b, and the axis between them.
struct FacingPair {
  int a, b;
  Eigen::Vector3d axis;  // from b's normal to a's
};

// The vertical RANSAC planes of the cloud (floor and ceiling removed first), largest first.
std::vector<WallPlaneFit> verticalCandidates(const std::vector<Eigen::Vector3f>& cloud_O,
                                             const WallExtractionOptions& options) {
  auto down = downsampled(cloud_O, options.voxel_m);
  auto remaining = withoutHorizontalSlabs(*down, options.voxel_m > 0 ? options.voxel_m : 0.05,
                                          options.horizontal_peak_factor);
  std::vector<WallPlaneFit> candidates;
  for (const WallPlaneFit& w : ransacPlanes(remaining, pcl::SACMODEL_PARALLEL_PLANE,
                                            std::asin(std::clamp(options.max_normal_z, 0.0, 1.0)),
                                            options.distance_threshold_m, options.max_planes,
                                            options.min_inliers, options.ransac_max_iterations)) {
    if (std::abs(w.normal.z()) <= options.max_normal_z) candidates.push_back(w);
  }
  return candidates;
}

// Two pairs of facing planes, the pairs perpendicular, with the most points (within
// `tol` rad); false if there are none.
bool bestPerpendicularPairs(const std::vector<WallPlaneFit>& candidates, double tol,
                            FacingPair* first, FacingPair* second) {
  std::vector<FacingPair> pairs;
  for (size_t a = 0; a < candidates.size(); ++a) {
    for (size_t b = a + 1; b < candidates.size(); ++b) {
      if (angleBetween(candidates[a].normal, -candidates[b].normal) <= tol) {
        pairs.push_back({static_cast<int>(a), static_cast<int>(b),
                         (candidates[a].normal - candidates[b].normal).normalized()});
      }
    }
  }
  int best_score = -1;
  const FacingPair* best[2] = {nullptr, nullptr};
  for (size_t p = 0; p < pairs.size(); ++p) {
    for (size_t q = p + 1; q < pairs.size(); ++q) {
      const FacingPair& P = pairs[p];
      const FacingPair& Q = pairs[q];
      if (P.a == Q.a || P.a == Q.b || P.b == Q.a || P.b == Q.b) continue;
      if (std::abs(angleBetween(P.axis, Q.axis) - M_PI / 2) > tol) continue;
      const int score = candidates[P.a].inliers + candidates[P.b].inliers +
                        candidates[Q.a].inliers + candidates[Q.b].inliers;
      if (score > best_score) {
        best_score = score;
        best[0] = &P;
        best[1] = &Q;
      }
    }
  }
  if (best_score < 0) return false;
  *first = *best[0];
  *second = *best[1];
  return true;
}

// The two pairs' walls in the order of WallExtraction::walls: [0] normal ~ +Y, [1] ~ +X,
// [2] ~ -Y, [3] ~ -X.
std::vector<WallPlaneFit> orderedWalls(const std::vector<WallPlaneFit>& candidates,
                                       const FacingPair& first, const FacingPair& second) {
  const FacingPair* y_pair = &first;
  const FacingPair* x_pair = &second;
  if (std::abs(y_pair->axis.y()) < std::abs(x_pair->axis.y())) std::swap(y_pair, x_pair);
  std::vector<WallPlaneFit> ordered(4);
  const auto place = [&](const FacingPair* pr, int slot_pos, int slot_neg, int coord) {
    const WallPlaneFit& a = candidates[pr->a];
    const WallPlaneFit& b = candidates[pr->b];
    const bool a_pos = a.normal[coord] >= b.normal[coord];
    ordered[slot_pos] = a_pos ? a : b;
    ordered[slot_neg] = a_pos ? b : a;
  };
  place(y_pair, 0, 2, 1);
  place(x_pair, 1, 3, 0);
  return ordered;
}

}  // namespace

WallExtraction extractWalls(const std::vector<Eigen::Vector3f>& cloud_O,
                            const WallExtractionOptions& options) {
  WallExtraction result;
  if (cloud_O.empty()) {
    result.reason = "empty cloud";
    return result;
  }
  // Vertical planes, largest first.
  const std::vector<WallPlaneFit> candidates = verticalCandidates(cloud_O, options);
  result.candidate_planes = static_cast<int>(candidates.size());
  if (candidates.size() < 4) {
    result.reason = "only " + std::to_string(candidates.size()) +
                    " vertical plane(s) of at least " + std::to_string(options.min_inliers) +
                    " points (4 walls needed)";
    return result;
  }
  FacingPair first, second;
  if (!bestPerpendicularPairs(candidates, options.parallel_tolerance_deg * kDegToRad, &first,
                              &second)) {
    result.reason = "no two perpendicular pairs of facing walls among " +
                    std::to_string(candidates.size()) + " vertical planes";
    return result;
  }
  // Refit on the full-resolution cloud (indices into cloud_O; non-finite points never
  // come within the distance of a plane).
  result.walls =
      refitWalls(cloud_O, orderedWalls(candidates, first, second), options.distance_threshold_m);
  for (const auto& w : result.walls) {
    if (w.inliers < 3) {
      result.walls.clear();
      result.reason = "a wall lost its points in the full-resolution refit";
      return result;
    }
  }
  return result;
}

}  // namespace sweepmap
