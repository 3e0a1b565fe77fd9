// A room's planes and dimensions: see calib/room_planes.hpp.
#include "calib/room_planes.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>

namespace sweepmap {

Eigen::Vector3d inlierCentroid(const std::vector<Eigen::Vector3f>& cloud,
                               const std::vector<int>& idx) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i : idx) c += cloud[static_cast<size_t>(i)].cast<double>();
  return idx.empty() ? c : Eigen::Vector3d(c / static_cast<double>(idx.size()));
}

double signedDistance(const WallPlaneFit& p, const Eigen::Vector3d& x) {
  return p.normal.dot(x) + p.offset;
}

// Distance of two near-parallel planes: the mean of each one's distance from the other's
// inlier centroid (symmetric; exact for parallel planes).
double planeDistance(const WallPlaneFit& a, const std::vector<Eigen::Vector3f>& cloud_a,
                     const WallPlaneFit& b, const std::vector<Eigen::Vector3f>& cloud_b) {
  return 0.5 * (std::abs(signedDistance(a, inlierCentroid(cloud_b, b.inlier_indices))) +
                std::abs(signedDistance(b, inlierCentroid(cloud_a, a.inlier_indices))));
}

RoomPlanes findRoomPlanes(const std::vector<Eigen::Vector3f>& cloud,
                          const WallExtractionOptions& wo) {
  RoomPlanes r;
  const WallExtraction walls = extractWalls(cloud, wo);
  r.walls = walls.walls;
  if (r.walls.empty()) r.reason = "walls: " + walls.reason;
  PlaneExtractionOptions ho;
  ho.orientation = PlaneExtractionOptions::Orientation::kHorizontal;
  ho.max_planes = 4;
  const auto horizontal = extractPlanes(cloud, ho);
  // Height of a horizontal plane: z where it crosses the vertical through its centroid.
  const auto height = [&](const WallPlaneFit& p) {
    return inlierCentroid(cloud, p.inlier_indices).z();
  };
  for (const WallPlaneFit& p : horizontal) {
    if (!r.floor || height(p) < height(*r.floor)) r.floor = p;
    if (!r.ceiling || height(p) > height(*r.ceiling)) r.ceiling = p;
  }
  if (horizontal.size() < 2) {
    r.floor.reset();
    r.ceiling.reset();
    r.reason += (r.reason.empty() ? "" : "; ") + std::string("fewer than two horizontal planes");
  }
  return r;
}

RoomDims roomDims(const RoomPlanes& p, const std::vector<Eigen::Vector3f>& cloud) {
  RoomDims d;
  if (p.walls.size() == 4) {
    const double y = planeDistance(p.walls[0], cloud, p.walls[2], cloud);
    const double x = planeDistance(p.walls[1], cloud, p.walls[3], cloud);
    d.L1 = std::max(x, y);
    d.L2 = std::min(x, y);
  }
  if (p.floor && p.ceiling) d.L3 = planeDistance(*p.floor, cloud, *p.ceiling, cloud);
  return d;
}

namespace {

// The range at which the ray from o along `ray` (any length) meets the plane (n, d), if it runs
// towards it.
std::optional<double> predictedRange(const Eigen::Vector3d& n, double d, const Eigen::Vector3d& o,
                                     const Eigen::Vector3d& ray) {
  const double h = n.dot(o) + d;  // the origin's signed distance from the plane
  const double along = n.dot(ray);
  if (!(along * h < 0)) return std::nullopt;
  return -h / along * ray.norm();
}

// Whether the ray o -> p is one of the plane's own by the ranges the planes predict: it runs
// towards the plane, clear of range_max_m and of every `nearer` plane (see refinePlane).
bool ownRay(const Eigen::Vector3d& n, double d, const Eigen::Vector3d& o, const Eigen::Vector3d& p,
            const RangeNoise& noise, const std::vector<PlaneEquation>& nearer) {
  if (noise.range_max_m <= 0 && nearer.empty()) return true;
  const Eigen::Vector3d ray = p - o;
  const std::optional<double> r = predictedRange(n, d, o, ray);
  if (!r) return false;
  if (noise.range_max_m > 0 &&
      *r > noise.range_max_m * (1.0 - noise.window_sigmas * noise.fraction))
    return false;
  const double margin = noise.window_sigmas * std::hypot(noise.fraction * *r, noise.floor_m);
  for (const PlaneEquation& q : nearer) {
    const std::optional<double> rq = predictedRange(q.normal, q.offset, o, ray);
    if (rq && *rq < *r + margin) return false;
  }
  return true;
}

// The points of `plane`'s window (each within window_sigmas of its sigma, its own ray by
// ownRay), with their weights.
void planeWindow(const std::vector<Eigen::Vector3f>& cloud,
                 const std::vector<Eigen::Vector3f>& origins, const Eigen::Vector3d& n, double d,
                 const RangeNoise& noise, const std::vector<PlaneEquation>& nearer,
                 std::vector<int>* idx, std::vector<double>* w) {
  idx->clear();
  w->clear();
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud[i].cast<double>(), o = origins[i].cast<double>();
    const double h = n.dot(o) + d;  // the origin's signed distance from the plane
    const double s = std::hypot(noise.fraction * h, noise.floor_m);
    if (!(std::abs(n.dot(p) + d) <= noise.window_sigmas * s)) continue;
    if (!ownRay(n, d, o, p, noise, nearer)) continue;
    idx->push_back(int(i));
    w->push_back(1.0 / (s * s));
  }
}

}  // namespace

RefinedPlane refinePlane(const std::vector<Eigen::Vector3f>& cloud,
                         const std::vector<Eigen::Vector3f>& origins, const WallPlaneFit& start,
                         const RangeNoise& noise, const std::vector<PlaneEquation>& nearer) {
  RefinedPlane r;
  r.normal = start.normal.normalized();
  r.offset = start.offset / std::max(1e-12, start.normal.norm());
  std::vector<int> last;
  for (int it = 0; it < noise.iterations; ++it) {
    std::vector<int> idx;
    std::vector<double> w;
    planeWindow(cloud, origins, r.normal, r.offset, noise, nearer, &idx, &w);
    if (idx.size() < 10) {
      r.ok = false;
      return r;
    }
    double sw = 0.0;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < idx.size(); ++k) {
      c += w[k] * cloud[size_t(idx[k])].cast<double>();
      sw += w[k];
    }
    c /= sw;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t k = 0; k < idx.size(); ++k) {
      const Eigen::Vector3d e = cloud[size_t(idx[k])].cast<double>() - c;
      cov += w[k] * e * e.transpose();
    }
    Eigen::Vector3d n = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
    if (n.dot(r.normal) < 0) n = -n;
    r.normal = n;
    r.offset = -n.dot(c);
    r.centroid = c;
    r.inliers = idx;
    r.weights = w;
    r.ok = true;
    if (idx == last) break;
    last = std::move(idx);
  }
  return r;
}

double refinedDistance(const RefinedPlane& a, const RefinedPlane& b) {
  return 0.5 * (std::abs(a.normal.dot(b.centroid) + a.offset) +
                std::abs(b.normal.dot(a.centroid) + b.offset));
}

RoomDims refinedRoomDims(const RoomPlanes& p, const std::vector<Eigen::Vector3f>& cloud,
                         const std::vector<Eigen::Vector3f>& origins, const RangeNoise& noise) {
  // The planes in this order: the four walls (extractWalls' order), the floor, the ceiling.
  std::vector<WallPlaneFit> start;
  if (p.walls.size() == 4) start = p.walls;
  if (p.floor && p.ceiling) start.insert(start.end(), {*p.floor, *p.ceiling});
  std::vector<RefinedPlane> alone;
  for (const WallPlaneFit& s : start) alone.push_back(refinePlane(cloud, origins, s, noise));
  std::vector<RefinedPlane> refined;
  for (size_t i = 0; i < alone.size(); ++i) {
    std::vector<PlaneEquation> nearer;
    for (size_t j = 0; j < alone.size(); ++j) {
      if (j != i && alone[j].ok) nearer.push_back({alone[j].normal, alone[j].offset});
    }
    // From the plane refined alone: the others' rays leave only its edges, so it starts near.
    WallPlaneFit from;
    from.normal = alone[i].normal;
    from.offset = alone[i].offset;
    refined.push_back(alone[i].ok ? refinePlane(cloud, origins, from, noise, nearer) : alone[i]);
  }
  const auto distance = [&](size_t a, size_t b) -> std::optional<double> {
    if (!refined[a].ok || !refined[b].ok) return std::nullopt;
    return refinedDistance(refined[a], refined[b]);
  };
  RoomDims d;
  const size_t f = p.walls.size() == 4 ? 4 : 0;  // the floor's index
  if (f == 4) {
    const std::optional<double> y = distance(0, 2);
    const std::optional<double> x = distance(1, 3);
    if (x && y) {
      d.L1 = std::max(*x, *y);
      d.L2 = std::min(*x, *y);
    }
  }
  if (p.floor && p.ceiling) d.L3 = distance(f, f + 1);
  return d;
}

}  // namespace sweepmap
