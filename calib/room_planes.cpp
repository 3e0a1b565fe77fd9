// A room's planes and dimensions: see calib/room_planes.hpp.
#include "calib/room_planes.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <utility>

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

// A region of a plane left out as clutter: the rays that meet the plane with in-plane
// coordinates (along e1, e2) within [lo, hi].
struct ClutterBox {
  Eigen::Vector3d e1, e2;
  Eigen::Vector2d lo, hi;
  double sigmas = 0.0;  // how far its region stood out
};

// Where the ray o -> p meets the plane (n, d), if it runs towards it.
std::optional<Eigen::Vector3d> meetingPoint(const Eigen::Vector3d& n, double d,
                                            const Eigen::Vector3d& o, const Eigen::Vector3d& p) {
  const Eigen::Vector3d ray = p - o;
  const std::optional<double> r = predictedRange(n, d, o, ray);
  if (!r) return std::nullopt;
  return Eigen::Vector3d(o + ray.normalized() * *r);
}

bool inClutter(const std::vector<ClutterBox>& boxes, const Eigen::Vector3d& s) {
  for (const ClutterBox& b : boxes) {
    const Eigen::Vector2d c(b.e1.dot(s), b.e2.dot(s));
    if ((c.array() >= b.lo.array()).all() && (c.array() <= b.hi.array()).all()) return true;
  }
  return false;
}

// The points of `plane`'s window (each within window_sigmas of its sigma, its own ray by
// ownRay, not meeting the plane in a clutter box), with their weights.
void planeWindow(const std::vector<Eigen::Vector3f>& cloud,
                 const std::vector<Eigen::Vector3f>& origins, const Eigen::Vector3d& n, double d,
                 const RangeNoise& noise, const std::vector<PlaneEquation>& nearer,
                 const std::vector<ClutterBox>& clutter, std::vector<int>* idx,
                 std::vector<double>* w) {
  idx->clear();
  w->clear();
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud[i].cast<double>(), o = origins[i].cast<double>();
    const double h = n.dot(o) + d;  // the origin's signed distance from the plane
    const double s = std::hypot(noise.fraction * h, noise.floor_m);
    if (!(std::abs(n.dot(p) + d) <= noise.window_sigmas * s)) continue;
    if (!ownRay(n, d, o, p, noise, nearer)) continue;
    if (!clutter.empty()) {
      const std::optional<Eigen::Vector3d> meets = meetingPoint(n, d, o, p);
      if (meets && inClutter(clutter, *meets)) continue;
    }
    idx->push_back(int(i));
    w->push_back(1.0 / (s * s));
  }
}

double weightOf(const RefinedPlane& r) {
  double w = 0.0;
  for (double x : r.weights) w += x;
  return w;
}

// In-plane axes of the normal n: horizontal for a wall, x and y for the floor and the ceiling.
void planeAxes(const Eigen::Vector3d& n, Eigen::Vector3d* e1, Eigen::Vector3d* e2) {
  *e1 = n.cross(Eigen::Vector3d::UnitZ());
  if (e1->norm() < 0.5) *e1 = Eigen::Vector3d::UnitY().cross(n);
  e1->normalize();
  *e2 = n.cross(*e1);
}

// RefinedPlane::offset_sigma of r's inliers: the weighted mean's sigma with the weighted
// deviations summed per in-plane cell first (the sandwich over cells, with its small-sample
// factor), or the points' own (1 / sum of the weights, times chi2 per dof when above 1) if
// larger. `cells_out`: how many cells the inliers fall in.
double offsetSigma(const std::vector<Eigen::Vector3f>& cloud, const RefinedPlane& r,
                   int* cells_out) {
  Eigen::Vector3d e1, e2;
  planeAxes(r.normal, &e1, &e2);
  std::map<std::pair<int64_t, int64_t>, double> cells;
  double sw = 0.0, chi2 = 0.0;
  for (size_t k = 0; k < r.inliers.size(); ++k) {
    const Eigen::Vector3d p = cloud[size_t(r.inliers[k])].cast<double>();
    const double e = r.normal.dot(p) + r.offset;
    cells[{int64_t(std::floor(e1.dot(p) / kOffsetClusterM)),
           int64_t(std::floor(e2.dot(p) / kOffsetClusterM))}] += r.weights[k] * e;
    sw += r.weights[k];
    chi2 += r.weights[k] * e * e;
  }
  *cells_out = int(cells.size());
  if (!(sw > 0.0)) return 0.0;
  const double dof = std::max(1.0, double(r.inliers.size()) - 3.0);
  const double own = std::sqrt(std::max(1.0, chi2 / dof) / sw);
  if (cells.size() < 2) return own;
  double ss = 0.0;
  for (const auto& [cell, sum] : cells) ss += sum * sum;
  const double m = double(cells.size());
  return std::max(own, std::sqrt(ss * m / (m - 1.0)) / sw);
}

// The window's fixed point from `r`'s plane (refinePlane without the clutter search).
void refineFixedPoint(const std::vector<Eigen::Vector3f>& cloud,
                      const std::vector<Eigen::Vector3f>& origins, const RangeNoise& noise,
                      const std::vector<PlaneEquation>& nearer,
                      const std::vector<ClutterBox>& clutter, RefinedPlane* r) {
  std::vector<int> last;
  for (int it = 0; it < noise.iterations; ++it) {
    std::vector<int> idx;
    std::vector<double> w;
    planeWindow(cloud, origins, r->normal, r->offset, noise, nearer, clutter, &idx, &w);
    if (idx.size() < 10) {
      r->ok = false;
      return;
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
    if (n.dot(r->normal) < 0) n = -n;
    r->normal = n;
    r->offset = -n.dot(c);
    r->centroid = c;
    r->inliers = idx;
    r->weights = w;
    r->ok = true;
    if (idx == last) break;
    last = std::move(idx);
  }
  if (r->ok) r->offset_sigma = offsetSigma(cloud, *r, &r->offset_cells);
}

// The plane's inliers binned by where their rays meet it, in cells of `cell` along e1, e2:
// per cell the sum of the weights and of the weighted offsets towards the lidar, as 2D prefix
// sums (entry (i, j): cells below i along e1 and below j along e2).
struct CellSums {
  Eigen::Vector3d e1, e2;
  Eigen::Vector2d lo;
  double cell = 0.0;
  int nu = 0, nv = 0;
  Eigen::MatrixXd W, S;
  double sum(const Eigen::MatrixXd& m, int u0, int u1, int v0, int v1) const {
    return m(u1 + 1, v1 + 1) - m(u0, v1 + 1) - m(u1 + 1, v0) + m(u0, v0);
  }
};

CellSums cellSums(const std::vector<Eigen::Vector3f>& cloud,
                  const std::vector<Eigen::Vector3f>& origins, const RefinedPlane& r,
                  const ClutterSearch& search) {
  CellSums c;
  const Eigen::Vector3d& n = r.normal;
  planeAxes(n, &c.e1, &c.e2);
  struct Item {
    Eigen::Vector2d at;
    double w, rho;
  };
  std::vector<Item> items;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
  for (size_t k = 0; k < r.inliers.size(); ++k) {
    const Eigen::Vector3d p = cloud[size_t(r.inliers[k])].cast<double>();
    const Eigen::Vector3d o = origins[size_t(r.inliers[k])].cast<double>();
    const std::optional<Eigen::Vector3d> s = meetingPoint(n, r.offset, o, p);
    if (!s) continue;
    const double h = n.dot(o) + r.offset;
    items.push_back({Eigen::Vector2d(c.e1.dot(*s), c.e2.dot(*s)), r.weights[k],
                     (n.dot(p) + r.offset) * (h < 0 ? -1.0 : 1.0)});
    lo = lo.cwiseMin(items.back().at);
    hi = hi.cwiseMax(items.back().at);
  }
  if (items.empty()) return c;
  // At most 64 cells a side: the rectangles are (cells a side)^4 / 4.
  c.cell = std::max({search.cell_m, (hi - lo).maxCoeff() / 63.0, 1e-3});
  c.lo = lo;
  c.nu = int((hi.x() - lo.x()) / c.cell) + 1;
  c.nv = int((hi.y() - lo.y()) / c.cell) + 1;
  c.W = Eigen::MatrixXd::Zero(c.nu + 1, c.nv + 1);
  c.S = c.W;
  for (const Item& it : items) {
    const int u = std::min(c.nu - 1, int((it.at.x() - lo.x()) / c.cell));
    const int v = std::min(c.nv - 1, int((it.at.y() - lo.y()) / c.cell));
    c.W(u + 1, v + 1) += it.w;
    c.S(u + 1, v + 1) += it.w * it.rho;
  }
  for (int u = 1; u <= c.nu; ++u) {
    for (int v = 1; v <= c.nv; ++v) {
      c.W(u, v) += c.W(u - 1, v) + c.W(u, v - 1) - c.W(u - 1, v - 1);
      c.S(u, v) += c.S(u - 1, v) + c.S(u, v - 1) - c.S(u - 1, v - 1);
    }
  }
  return c;
}

// The best rectangle of a far wall's noisy cells may cover a whiteboard in part: it is grown
// by this many cells each way (more leaves out more of the wall, whose noise then grows).
constexpr int kClutterGrowCells = 1;

// The rectangle of cells (less than half of the plane's weight) that stands proud of the rest
// by the most sigmas, if by at least search.min_m and min_sigmas; grown by kClutterGrowCells.
std::optional<ClutterBox> findClutter(const std::vector<Eigen::Vector3f>& cloud,
                                      const std::vector<Eigen::Vector3f>& origins,
                                      const RefinedPlane& r, const ClutterSearch& search,
                                      double min_sigmas) {
  const CellSums c = cellSums(cloud, origins, r, search);
  if (c.nu == 0) return std::nullopt;
  const double Wt = c.W(c.nu, c.nv), St = c.S(c.nu, c.nv);
  double best = min_sigmas;
  std::optional<std::array<int, 4>> at;
  for (int u0 = 0; u0 < c.nu; ++u0) {
    for (int u1 = u0; u1 < c.nu; ++u1) {
      for (int v0 = 0; v0 < c.nv; ++v0) {
        for (int v1 = v0; v1 < c.nv; ++v1) {
          const double Win = c.sum(c.W, u0, u1, v0, v1);
          if (!(Win > 0.0) || 2.0 * Win > Wt) continue;
          const double Sin = c.sum(c.S, u0, u1, v0, v1);
          const double proud = Sin / Win - (St - Sin) / (Wt - Win);
          if (proud < search.min_m) continue;
          const double z = proud / std::sqrt(1.0 / Win + 1.0 / (Wt - Win));
          if (z > best) {
            best = z;
            at = {u0, u1, v0, v1};
          }
        }
      }
    }
  }
  if (!at) return std::nullopt;
  const auto [u0, u1, v0, v1] = *at;
  ClutterBox b;
  b.e1 = c.e1;
  b.e2 = c.e2;
  b.lo = c.lo + c.cell * Eigen::Vector2d(u0 - kClutterGrowCells, v0 - kClutterGrowCells);
  b.hi = c.lo + c.cell * Eigen::Vector2d(u1 + 1 + kClutterGrowCells, v1 + 1 + kClutterGrowCells);
  b.sigmas = best;
  return b;
}

}  // namespace

RefinedPlane refinePlane(const std::vector<Eigen::Vector3f>& cloud,
                         const std::vector<Eigen::Vector3f>& origins, const WallPlaneFit& start,
                         const RangeNoise& noise, const std::vector<PlaneEquation>& nearer,
                         const std::optional<ClutterSearch>& search) {
  RefinedPlane r;
  r.normal = start.normal.normalized();
  r.offset = start.offset / std::max(1e-12, start.normal.norm());
  std::vector<ClutterBox> clutter;
  refineFixedPoint(cloud, origins, noise, nearer, clutter, &r);
  const double whole = weightOf(r);
  // The plane with `box` left out too, if it keeps enough of its weight: a plane that would
  // lose more than max_share is smeared or bent, not cluttered (each region taken out on one
  // side would push it further back).
  const auto without = [&](const ClutterBox& box) -> std::optional<RefinedPlane> {
    std::vector<ClutterBox> more = clutter;
    more.push_back(box);
    RefinedPlane next = r;
    refineFixedPoint(cloud, origins, noise, nearer, more, &next);
    if (!next.ok || weightOf(next) < (1.0 - search->max_share) * whole) return std::nullopt;
    next.clutter_regions = int(more.size());
    return next;
  };
  while (r.ok && search && int(clutter.size()) < search->max_regions) {
    // One scan for both: the region that stands out most, certain clutter or maybe.
    const std::optional<ClutterBox> box =
        findClutter(cloud, origins, r, *search, std::min(search->ambiguous_sigmas, search->sigmas));
    if (!box) break;
    if (!(box->sigmas > search->sigmas)) {
      // Nothing stands out for certain; a region that may be clutter widens the sigma.
      const std::optional<RefinedPlane> alt = without(*box);
      if (alt) {
        r.ambiguity_m = std::abs(alt->normal.dot(r.centroid) + alt->offset);
        r.offset_sigma = std::hypot(r.offset_sigma, r.ambiguity_m);
      }
      break;
    }
    std::optional<RefinedPlane> next = without(*box);
    if (!next) break;
    clutter.push_back(*box);
    r = std::move(*next);
  }
  return r;
}

double refinedDistanceSigma(const RefinedPlane& a, const RefinedPlane& b) {
  return std::hypot(a.offset_sigma, b.offset_sigma);
}

double refinedDistance(const RefinedPlane& a, const RefinedPlane& b) {
  return 0.5 * (std::abs(a.normal.dot(b.centroid) + a.offset) +
                std::abs(b.normal.dot(a.centroid) + b.offset));
}

RoomDims refinedRoomDims(const RoomPlanes& p, const std::vector<Eigen::Vector3f>& cloud,
                         const std::vector<Eigen::Vector3f>& origins, const RangeNoise& noise,
                         const ClutterSearch& clutter) {
  // The planes in this order: the four walls (extractWalls' order), the floor, the ceiling.
  std::vector<WallPlaneFit> start;
  if (p.walls.size() == 4) start = p.walls;
  if (p.floor && p.ceiling) start.insert(start.end(), {*p.floor, *p.ceiling});
  // Alone without the clutter search: the others' strips along its edges would stand proud.
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
    refined.push_back(alone[i].ok ? refinePlane(cloud, origins, from, noise, nearer, clutter)
                                  : alone[i]);
  }
  const auto distance = [&](size_t a, size_t b) -> std::optional<double> {
    if (!refined[a].ok || !refined[b].ok) return std::nullopt;
    return refinedDistance(refined[a], refined[b]);
  };
  const auto sigma = [&](size_t a, size_t b) {
    return refinedDistanceSigma(refined[a], refined[b]);
  };
  RoomDims d;
  const size_t f = p.walls.size() == 4 ? 4 : 0;  // the floor's index
  if (f == 4) {
    const std::optional<double> y = distance(0, 2);
    const std::optional<double> x = distance(1, 3);
    if (x && y) {
      const bool x_longer = *x >= *y;
      d.L1 = x_longer ? *x : *y;
      d.L2 = x_longer ? *y : *x;
      d.L1_sigma = x_longer ? sigma(1, 3) : sigma(0, 2);
      d.L2_sigma = x_longer ? sigma(0, 2) : sigma(1, 3);
    }
  }
  if (p.floor && p.ceiling) {
    d.L3 = distance(f, f + 1);
    if (d.L3) d.L3_sigma = sigma(f, f + 1);
  }
  return d;
}

}  // namespace sweepmap
