// The fast point-to-plane alignment of a drive's two passes: see calib/overlap_alignment.hpp.
#include "calib/overlap_alignment.hpp"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <map>
#include <thread>

#include "calib/rotating_geometry.hpp"
#include "core/angles.hpp"

namespace sweepmap {
namespace {

constexpr size_t kChunk = 2048;  // queries per chunk: the unit of work and of reduction
constexpr int kMaxNb = 32;

// Runs f(chunk, begin, end) over [0, n) in chunks of kChunk on `threads` threads. Callers
// write each chunk's results to its own slot, and reduce the slots in chunk order.
template <class F>
void forChunks(size_t n, int threads, F f) {
  const size_t chunks = (n + kChunk - 1) / kChunk;
  std::atomic<size_t> next{0};
  const auto work = [&] {
    for (size_t c = next++; c < chunks; c = next++) f(c, c * kChunk, std::min(n, (c + 1) * kChunk));
  };
  const int t = std::max(1, std::min<int>(threads, int(chunks)));
  std::vector<std::thread> pool;
  for (int k = 1; k < t; ++k) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
}

int threadCount(int requested) {
  if (requested > 0) return requested;
  return std::max(1, int(std::thread::hardware_concurrency()));
}

// The world cloud of one round: every covered ray's point, and a k-d tree per half.
struct Cloud {
  std::vector<Eigen::Vector3d> p, dir;
  std::vector<char> covered;
  std::vector<int> half_index[2];  // tree index -> ray, for the right (0) and left (1) halves
  pcl::KdTreeFLANN<pcl::PointXYZ> tree[2];
  bool has_tree[2] = {false, false};
  // Per half, the centroids of its points in cubes of plane_voxel_m: the local planes and
  // their flatness, over the whole patch radius at a fraction of the points.
  std::vector<Eigen::Vector3d> voxel[2];
  pcl::KdTreeFLANN<pcl::PointXYZ> voxel_tree[2];
};

using CubeKey = std::array<int64_t, 3>;

CubeKey cubeOf(const Eigen::Vector3d& p, double size) {
  return {int64_t(std::floor(p.x() / size)), int64_t(std::floor(p.y() / size)),
          int64_t(std::floor(p.z() / size))};
}

// The rays `rays_in` grouped by the cube of `at(ray)`: rays in the cubes' key order, and each
// cube's range of them.
// Keys within +-2^20 cubes of the origin (42 km at 4 cm) are sorted packed into one word, 21
// bits a coordinate, in the same order: a third of the time of sorting the arrays.
template <class At>
void groupByCube(const std::vector<int>& rays_in, double size, At at, std::vector<CubeKey>* keys,
                 std::vector<int>* rays_out, std::vector<size_t>* begin) {
  constexpr int64_t kHalf = int64_t(1) << 20;
  std::vector<std::pair<CubeKey, int>> keyed;
  keyed.reserve(rays_in.size());
  bool packable = true;
  for (int i : rays_in) {
    keyed.push_back({cubeOf(at(i), size), i});
    for (int64_t c : keyed.back().first) packable = packable && c >= -kHalf && c < kHalf;
  }
  if (packable) {
    std::vector<std::pair<uint64_t, int>> packed(keyed.size());
    for (size_t i = 0; i < keyed.size(); ++i) {
      const CubeKey& k = keyed[i].first;
      packed[i] = {
          uint64_t(k[0] + kHalf) << 42 | uint64_t(k[1] + kHalf) << 21 | uint64_t(k[2] + kHalf),
          keyed[i].second};
    }
    std::sort(packed.begin(), packed.end());
    constexpr uint64_t kMask = (uint64_t(1) << 21) - 1;
    for (size_t i = 0; i < keyed.size(); ++i) {
      const uint64_t w = packed[i].first;
      keyed[i] = {{int64_t(w >> 42) - kHalf, int64_t((w >> 21) & kMask) - kHalf,
                   int64_t(w & kMask) - kHalf},
                  packed[i].second};
    }
  } else {
    std::sort(keyed.begin(), keyed.end());
  }
  keys->clear();
  rays_out->clear();
  begin->assign(1, 0);
  for (size_t i = 0; i < keyed.size(); ++i) {
    rays_out->push_back(keyed[i].second);
    if (i + 1 == keyed.size() || keyed[i + 1].first != keyed[i].first) {
      keys->push_back(keyed[i].first);
      begin->push_back(i + 1);
    }
  }
}

// The mean of at(i) over each cube's rays, as groupByCube gave them.
template <class At>
std::vector<Eigen::Vector3d> cubeMeans(const std::vector<int>& order,
                                       const std::vector<size_t>& begin, At at) {
  std::vector<Eigen::Vector3d> out;
  for (size_t k = 0; k + 1 < begin.size(); ++k) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (size_t j = begin[k]; j < begin[k + 1]; ++j) sum += at(order[j]);
    out.push_back(sum / double(begin[k + 1] - begin[k]));
  }
  return out;
}

// The centroids of `pts` per cube of `size`, in the order of the cubes' keys.
std::vector<Eigen::Vector3d> voxelCentroids(const std::vector<Eigen::Vector3d>& pts, double size) {
  std::vector<int> all(pts.size()), order;
  for (size_t i = 0; i < pts.size(); ++i) all[i] = int(i);
  std::vector<CubeKey> keys;
  std::vector<size_t> begin;
  const auto point = [&](int i) { return pts[size_t(i)]; };
  groupByCube(all, size, point, &keys, &order, &begin);
  return cubeMeans(order, begin, point);
}

pcl::PointCloud<pcl::PointXYZ>::Ptr toPcl(const std::vector<Eigen::Vector3d>& pts) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (const auto& p : pts)
    cloud->push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
  return cloud;
}

void computePoints(const std::vector<OverlapRay>& rays, const OverlapModel& model, int threads,
                   Cloud* c) {
  c->p.assign(rays.size(), Eigen::Vector3d::Zero());
  c->dir.assign(rays.size(), Eigen::Vector3d::Zero());
  c->covered.assign(rays.size(), 0);
  forChunks(rays.size(), threads, [&](size_t, size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) c->covered[i] = model.point(i, &c->p[i], &c->dir[i], nullptr);
  });
}

void buildTrees(const std::vector<OverlapRay>& rays, double voxel_m, Cloud* c) {
  for (int h = 0; h < 2; ++h) {
    std::vector<Eigen::Vector3d> pts;
    c->half_index[h].clear();
    for (size_t i = 0; i < rays.size(); ++i) {
      if (!c->covered[i] || int(rays[i].left) != h) continue;
      c->half_index[h].push_back(int(i));
      pts.push_back(c->p[i]);
    }
    c->has_tree[h] = !pts.empty();
    if (!c->has_tree[h]) continue;
    c->tree[h].setInputCloud(toPcl(pts));
    c->voxel[h] = voxelCentroids(pts, voxel_m);
    c->voxel_tree[h].setInputCloud(toPcl(c->voxel[h]));
  }
}

// The voxel centroids of half h within radius of p (at most 64, nearest first).
int voxelsNear(const Cloud& c, int h, const Eigen::Vector3d& p, double radius,
               Eigen::Vector3d* out) {
  if (!c.has_tree[h]) return 0;
  std::vector<int> idx;
  std::vector<float> d2;
  c.voxel_tree[h].radiusSearch(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())), radius, idx,
                               d2, 64);
  for (size_t j = 0; j < idx.size(); ++j) out[j] = c.voxel[h][size_t(idx[j])];
  return int(idx.size());
}

// A query and the other pass's points whose local plane it is compared with.
struct Correspondence {
  int a;
  int nb[kMaxNb];
  int count;
  Eigen::Vector3d n;
  double trim_m;  // residuals beyond this are dropped after the first round
};

// Up to k rays of half h nearest to p within radius (ascending distance).
int nearest(const Cloud& c, int h, const Eigen::Vector3d& p, int k, double radius, int* out) {
  if (!c.has_tree[h]) return 0;
  std::vector<int> idx;
  std::vector<float> d2;
  c.tree[h].nearestKSearch(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())), k, idx, d2);
  int n = 0;
  for (size_t j = 0; j < idx.size() && n < k; ++j) {
    if (d2[j] <= radius * radius) out[n++] = c.half_index[h][size_t(idx[j])];
  }
  return n;
}

// The range a ray from `origin` along `dir` meets the plane (normal n through m) at.
double predictedRange(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                      const Eigen::Vector3d& n, const Eigen::Vector3d& m) {
  return std::abs(n.dot(m - origin)) / std::max(1e-9, std::abs(n.dot(dir)));
}

// One half's local plane around a point: the PCA plane of its voxel centroids within
// plane_radius_m (at least min_neighbours of them, planar), and their mean squared distance
// from it.
struct LocalPlane {
  bool ok = false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::UnitZ();
  double spread_m2 = 0.0;
};

LocalPlane fitLocalPlane(const Cloud& c, int h, const Eigen::Vector3d& at,
                         const MountingCalibrationOptions& o) {
  LocalPlane lp;
  Eigen::Vector3d patch[64];
  const int count = voxelsNear(c, h, at, o.plane_radius_m, patch);
  if (count < o.min_neighbours ||
      !fitPcaPlane(patch, count, o.max_planarity_ratio, 1e300, &lp.mean, &lp.n)) {
    return lp;
  }
  double var = 0.0;
  for (int i = 0; i < count; ++i) var += std::pow(lp.n.dot(patch[i] - lp.mean), 2);
  lp.spread_m2 = var / count;
  lp.ok = true;
  return lp;
}

// Whether a local plane is flat to within the range noise of the query's ray (at most along
// the normal) plus a millimetre. The noise is that of the range the plane predicts for the
// ray, not of the range measured: a limit from the measured range would pass the queries
// measured long more often than those measured short, and a noise-weighted one weigh them less
// (together 0.1 % of every range, taken up as the wheels' scale).
bool flatFor(const LocalPlane& lp, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
             const MountingCalibrationOptions& o) {
  if (!lp.ok) return false;
  const double sigma = o.range_noise_fraction * predictedRange(origin, dir, lp.n, lp.mean);
  return lp.spread_m2 <= 2.0 * sigma * sigma + 1e-6;
}

// The local planes of a search's queries, per half (right 0, left 1). With plane_cell_m > 0
// the queries whose points fell in one cube of that size share them, fitted around the mean
// of their points (the 4 cm voxels' radius search and PCA were about 90 % of a search's time
// on rig B, with every query fitting its own); else each query's are fitted around its point.
struct QueryPlanes {
  std::vector<int> slot;  // per query: its planes in `fit`
  std::vector<std::array<LocalPlane, 2>> fit;
};

// Which queries share their local planes: per ray, its group (-1: none yet). Fixed over the
// searches of one alignment, from the cubes the points fell in when the ray was first a query,
// so that a query's planes move with the parameters as smoothly as its point does: grouped
// anew at every search, the queries near a cube's face changed groups, and the solver needed
// half as many searches again.
struct PlaneGroups {
  std::vector<int> of_ray;
  int count = 0;
};

void groupQueries(const std::vector<int>& queries, const Cloud& c, double cell_m,
                  PlaneGroups* groups) {
  if (groups->of_ray.empty()) groups->of_ray.assign(c.p.size(), -1);
  std::vector<int> fresh;
  for (int i : queries) {
    if (groups->of_ray[size_t(i)] < 0) fresh.push_back(i);
  }
  std::vector<CubeKey> keys;
  std::vector<int> order;
  std::vector<size_t> begin;
  groupByCube(
      fresh, cell_m, [&](int i) { return c.p[size_t(i)]; }, &keys, &order, &begin);
  for (size_t k = 0; k + 1 < begin.size(); ++k, ++groups->count) {
    for (size_t j = begin[k]; j < begin[k + 1]; ++j)
      groups->of_ray[size_t(order[j])] = groups->count;
  }
}

QueryPlanes queryPlanes(const std::vector<int>& queries, const Cloud& c, const OverlapOptions& oo,
                        int threads, PlaneGroups* groups) {
  if (oo.plane_cell_m > 0.0) groupQueries(queries, c, oo.plane_cell_m, groups);
  QueryPlanes qp;
  qp.slot.resize(queries.size());
  std::vector<int> slot_of_group(size_t(groups->count), -1);
  std::vector<Eigen::Vector3d> sum;
  std::vector<int> count;
  for (size_t q = 0; q < queries.size(); ++q) {
    const int g = oo.plane_cell_m > 0.0 ? groups->of_ray[size_t(queries[q])] : -1;
    int slot = g >= 0 ? slot_of_group[size_t(g)] : -1;
    if (slot < 0) {  // the query's group is new to this search, or it has none
      slot = int(sum.size());
      if (g >= 0) slot_of_group[size_t(g)] = slot;
      sum.push_back(Eigen::Vector3d::Zero());
      count.push_back(0);
    }
    qp.slot[q] = slot;
    sum[size_t(slot)] += c.p[size_t(queries[q])];
    ++count[size_t(slot)];
  }
  qp.fit.resize(sum.size());
  forChunks(sum.size(), threads, [&](size_t, size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      const Eigen::Vector3d at = sum[i] / double(count[i]);
      for (int h = 0; h < 2; ++h) qp.fit[i][size_t(h)] = fitLocalPlane(c, h, at, oo.base);
    }
  });
  return qp;
}

// The local planes at query a: the other pass's (its normal and mean), and the one the
// query's own half sees there, which must agree (the query lies on that surface, not on
// another one near an edge). False if either is not flat or they disagree.
bool localPlane(const OverlapRay& ra, const Cloud& c, size_t a,
                const std::array<LocalPlane, 2>& fits, const MountingCalibrationOptions& o,
                Eigen::Vector3d* n, Eigen::Vector3d* mean) {
  const Eigen::Vector3d origin = c.p[a] - ra.range_m * c.dir[a];
  const LocalPlane& other = fits[ra.left ? 0 : 1];
  if (!flatFor(other, origin, c.dir[a], o)) return false;
  *mean = other.mean;
  *n = other.n;
  if (!o.check_own_plane) return true;
  const LocalPlane& own = fits[ra.left ? 1 : 0];
  return flatFor(own, origin, c.dir[a], o) &&
         std::abs(own.n.dot(*n)) >= std::cos(o.max_normal_angle_rad);
}

// Query a's correspondence, as the reference solver's planeResidual decides it: flat local
// planes that agree (localPlane), the other pass's points nearest within the plane (k nearest
// of its half, at least min_pass_gap_s away), not grazing, the query over the middle of the
// patch.
bool findCorrespondence(const std::vector<OverlapRay>& rays, const Cloud& c, int a,
                        const std::array<LocalPlane, 2>& fits, const OverlapOptions& oo,
                        Correspondence* out) {
  const MountingCalibrationOptions& o = oo.base;
  const OverlapRay& ra = rays[size_t(a)];
  const Eigen::Vector3d& pa = c.p[size_t(a)];
  Eigen::Vector3d n, plane_mean;
  if (!localPlane(ra, c, size_t(a), fits, o, &n, &plane_mean)) return false;
  const double sigma = o.range_noise_fraction * predictedRange(pa - ra.range_m * c.dir[size_t(a)],
                                                               c.dir[size_t(a)], n, plane_mean);
  if (o.max_incidence_rad < 0.5 * M_PI &&
      std::abs(c.dir[size_t(a)].dot(n)) < std::cos(o.max_incidence_rad)) {
    return false;
  }
  int cand[64];
  const int nc = nearest(c, ra.left ? 0 : 1, pa, std::min(64, oo.plane_neighbours),
                         o.neighbour_radius_m, cand);
  std::pair<double, int> order[64];
  int no = 0;
  for (int j = 0; j < nc; ++j) {
    if (std::abs(double(rays[size_t(cand[j])].utime - ra.utime)) < o.min_pass_gap_s * 1e6) continue;
    const Eigen::Vector3d off = c.p[size_t(cand[j])] - pa;
    const double d2 = (off - n * n.dot(off)).squaredNorm();
    if (d2 <= o.neighbour_radius_m * o.neighbour_radius_m) order[no++] = {d2, cand[j]};
  }
  if (no < o.min_neighbours) return false;
  std::sort(order, order + no);
  out->count = std::min({no, o.max_neighbours, kMaxNb});
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int j = 0; j < out->count; ++j) {
    out->nb[j] = order[j].second;
    mean += c.p[size_t(out->nb[j])];
  }
  mean /= double(out->count);
  if (o.max_incidence_rad < 0.5 * M_PI &&
      std::abs(c.dir[size_t(out->nb[0])].dot(n)) < std::cos(o.max_incidence_rad)) {
    return false;
  }
  const Eigen::Vector3d off = pa - mean;
  if ((off - n * n.dot(off)).norm() > 0.5 * o.neighbour_radius_m) return false;
  out->a = a;
  out->n = n;
  out->trim_m = std::max(o.min_trim_m, o.trim_noise_sigmas * sigma);
  return true;
}

// The covered rays within the query ranges whose index is a multiple of query_stride, with
// their correspondences.
std::vector<Correspondence> search(const std::vector<OverlapRay>& rays, const Cloud& c,
                                   const OverlapOptions& oo, int threads, PlaneGroups* plane_groups,
                                   int64_t* local_planes) {
  const MountingCalibrationOptions& o = oo.base;
  std::vector<int> queries;
  for (size_t i = 0; i < rays.size(); ++i) {
    // Strided by the ray's index, not by its count among the covered: the rays the track
    // covers change with the time offset, and would shift every query to its neighbour.
    if (!c.covered[i] || i % size_t(std::max(1, o.query_stride)) != 0) continue;
    if (rays[i].range_m < o.min_range_m || rays[i].range_m > o.max_range_m) continue;
    queries.push_back(int(i));
  }
  const QueryPlanes planes = queryPlanes(queries, c, oo, threads, plane_groups);
  std::vector<std::vector<Correspondence>> parts((queries.size() + kChunk - 1) / kChunk);
  forChunks(queries.size(), threads, [&](size_t chunk, size_t b, size_t e) {
    for (size_t q = b; q < e; ++q) {
      Correspondence corr;
      if (findCorrespondence(rays, c, queries[q], planes.fit[size_t(planes.slot[q])], oo, &corr))
        parts[chunk].push_back(corr);
    }
  });
  std::vector<Correspondence> all;
  for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
  *local_planes += int64_t(planes.fit.size());
  return all;
}

// One residual, linear in the parameter change: w (r + J dx), Cauchy loss at `scale`.
// Its fields are left unset at construction: the forming functions set every one, and a
// round's residuals (some 100 MB) are not zeroed first.
struct Residual {
  Residual() {}  // user-provided: with = default, vector::resize would zero each one
  double r, w, scale;
  Eigen::Matrix<double, 1, kMaxOverlapParameters> J;
  bool keep;
  Eigen::Vector3f at;   // the query's world point (its cluster for the sandwich covariance)
  double t_a_s, t_b_s;  // the query's and its neighbours' (mean) times [s], likewise
  double dof;           // its share of the degrees of freedom (less a patch's plane's)
};

Residual formResidual(const std::vector<OverlapRay>& rays, const OverlapModel& model,
                      const Correspondence& corr, const MountingCalibrationOptions& o) {
  Residual res;
  Eigen::Vector3d pa, da, pb, db, mean = Eigen::Vector3d::Zero();
  OverlapJacobian Ja, Jb, Jmean = OverlapJacobian::Zero();
  model.point(size_t(corr.a), &pa, &da, &Ja);
  // The range noise along the normal of a ray from its origin: that of the range the
  // neighbours' plane predicts for it (flatFor says why not the measured one).
  Eigen::Vector3d origins[kMaxNb];
  const auto variance = [&](const Eigen::Vector3d& origin) {
    const double s = o.range_noise_fraction * corr.n.dot(mean - origin);
    return s * s;
  };
  double t_b = 0.0;
  for (int j = 0; j < corr.count; ++j) {
    t_b += 1e-6 * double(rays[size_t(corr.nb[j])].utime - rays.front().utime);
    model.point(size_t(corr.nb[j]), &pb, &db, &Jb);
    origins[j] = pb - rays[size_t(corr.nb[j])].range_m * db;
    mean += pb;
    Jmean += Jb;
  }
  mean /= double(corr.count);
  double var_nb = 0.0;
  for (int j = 0; j < corr.count; ++j) var_nb += variance(origins[j]);
  Jmean /= double(corr.count);
  var_nb /= double(corr.count) * double(corr.count);
  res.r = corr.n.dot(pa - mean);
  res.J = corr.n.transpose() * (Ja - Jmean);
  res.at = pa.cast<float>();
  res.t_a_s = 1e-6 * double(rays[size_t(corr.a)].utime - rays.front().utime);
  res.t_b_s = t_b / double(corr.count);
  res.w = 1.0;
  res.scale = o.loss_scale_m;
  if (o.noise_weighting) {
    res.w = 1.0 / std::sqrt(variance(pa - rays[size_t(corr.a)].range_m * da) + var_nb +
                            o.model_sigma_m * o.model_sigma_m);
    res.scale = std::max(o.loss_scale_sigmas, o.loss_scale_m * res.w);
  }
  res.keep = true;
  res.dof = 1.0;
  return res;
}

// The residuals of `corrs`, into *out (its storage reused from round to round: a round's
// residuals take some 100 MB).
void formResiduals(const std::vector<OverlapRay>& rays, const OverlapModel& model,
                   const std::vector<Correspondence>& corrs, bool trim,
                   const MountingCalibrationOptions& o, int threads, std::vector<Residual>* out) {
  out->resize(corrs.size());
  forChunks(corrs.size(), threads, [&](size_t, size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      (*out)[i] = formResidual(rays, model, corrs[i], o);
      (*out)[i].keep = !trim || std::abs((*out)[i].r) <= corrs[i].trim_m;
    }
  });
}

// ------------------------------------------------------------------ plane adjustment
// The patches of a search: the rays of each cube of patch_m whose points lie on one plane
// seen by both passes, patch by patch.
struct Patches {
  std::vector<int> members;
  std::vector<size_t> begin;  // patch k: members[begin[k], begin[k + 1])
  size_t count() const { return begin.empty() ? 0 : begin.size() - 1; }
};

// One patch's points at the current estimate and its plane: the weighted centroid, the
// normal and the in-plane axes, and each point's range noise along the normal (that of the
// range the plane predicts for its ray, as flatFor says).
struct PatchFit {
  std::vector<Eigen::Vector3d> p;
  std::vector<double> sigma, w2;
  Eigen::Vector3d mean, n, u, v;
  Eigen::Vector3d ev;  // the weighted scatter's eigenvalues, ascending
};

// The weighted plane of the points with w2 > 0 (w2 their weights); false with fewer than 3.
bool weightedPlane(PatchFit* f) {
  double W = 0.0;
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < f->p.size(); ++i) {
    W += f->w2[i];
    m += f->w2[i] * f->p[i];
  }
  if (W <= 0.0) return false;
  m /= W;
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < f->p.size(); ++i)
    S += f->w2[i] * (f->p[i] - m) * (f->p[i] - m).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(S / W);
  f->mean = m;
  f->ev = es.eigenvalues();
  f->n = es.eigenvectors().col(0);
  int big = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(f->n(k)) > std::abs(f->n(big))) big = k;
  }
  if (f->n(big) < 0) f->n = -f->n;
  f->u = es.eigenvectors().col(2);
  f->v = f->n.cross(f->u);
  return true;
}

// Fits the patch of rays idx[0..count) at the points `pts` (dirs: the rays' world directions):
// unweighted first, then weighted by each point's range noise from that plane.
void fitPatch(const std::vector<OverlapRay>& rays, const int* idx, size_t count,
              const Eigen::Vector3d* pts, const Eigen::Vector3d* dirs,
              const MountingCalibrationOptions& o, PatchFit* f) {
  f->p.assign(pts, pts + count);
  f->w2.assign(count, 1.0);
  f->sigma.assign(count, 0.0);
  for (int pass = 0; pass < 2; ++pass) {
    weightedPlane(f);
    for (size_t i = 0; i < count; ++i) {
      const Eigen::Vector3d origin = pts[i] - rays[size_t(idx[i])].range_m * dirs[i];
      f->sigma[i] = o.range_noise_fraction * std::abs(f->n.dot(f->mean - origin));
      f->w2[i] = 1.0 / (f->sigma[i] * f->sigma[i] + o.model_sigma_m * o.model_sigma_m);
    }
  }
  weightedPlane(f);
}

// A patch's points farther from its plane than this many sigmas of their own range noise are
// not its (the room's planes use the same window).
constexpr double kPatchWindowSigmas = 3.0;

// The rays idx[0..count) of a half seen at least min_pass_gap_s from some ray of the other half
// (those within it of every one see the surface at the same moment as the other pass).
std::vector<int> passGated(const std::vector<OverlapRay>& rays, const int* idx, size_t count,
                           double min_pass_gap_s) {
  int64_t lo[2] = {INT64_MAX, INT64_MAX}, hi[2] = {INT64_MIN, INT64_MIN};
  for (size_t i = 0; i < count; ++i) {
    const OverlapRay& r = rays[size_t(idx[i])];
    lo[r.left] = std::min(lo[r.left], r.utime);
    hi[r.left] = std::max(hi[r.left], r.utime);
  }
  const double gap_us = min_pass_gap_s * 1e6;
  std::vector<int> kept;
  for (size_t i = 0; i < count; ++i) {
    const OverlapRay& r = rays[size_t(idx[i])];
    const int other = r.left ? 0 : 1;
    if (lo[other] == INT64_MAX) continue;
    if (double(r.utime - lo[other]) < gap_us && double(hi[other] - r.utime) < gap_us) continue;
    kept.push_back(idx[i]);
  }
  return kept;
}

// Whether the rays idx[0..count) (one cube's) form a patch: both halves (the passes, as
// passGated keeps them) hold min_neighbours points not grazing the plane, flat to within
// their noise, and each half's own plane agrees with the patch's. Returns the kept.
std::vector<int> patchMembers(const std::vector<OverlapRay>& rays, const Cloud& c, const int* idx,
                              size_t count, const MountingCalibrationOptions& o) {
  std::vector<int> kept = passGated(rays, idx, count, o.min_pass_gap_s);
  int per_half[2] = {0, 0};
  for (int i : kept) ++per_half[rays[size_t(i)].left];
  if (std::min(per_half[0], per_half[1]) < o.min_neighbours) return {};
  std::vector<Eigen::Vector3d> pts, dirs;
  PatchFit f;
  // The patch's plane, twice without the points beyond the window of their own noise (of
  // another surface: at a corner the floor's or the ceiling's points measured into a wall's
  // cube, which the wall's far, noisy rays' trim would keep).
  for (int pass = 0; pass < 3; ++pass) {
    if (pass > 0) {
      std::vector<int> in;
      for (size_t i = 0; i < kept.size(); ++i) {
        if (std::abs(f.n.dot(pts[i] - f.mean)) <= kPatchWindowSigmas * f.sigma[i] + 1e-3)
          in.push_back(kept[i]);
      }
      kept.swap(in);
      if (int(kept.size()) < 2 * o.min_neighbours) return {};
    }
    pts.clear();
    dirs.clear();
    for (int i : kept) {
      pts.push_back(c.p[size_t(i)]);
      dirs.push_back(c.dir[size_t(i)]);
    }
    fitPatch(rays, kept.data(), kept.size(), pts.data(), dirs.data(), o, &f);
  }
  per_half[0] = per_half[1] = 0;
  for (int i : kept) ++per_half[rays[size_t(i)].left];
  if (std::min(per_half[0], per_half[1]) < o.min_neighbours) return {};
  double noise = 0.0, chi2 = 0.0;
  for (size_t i = 0; i < kept.size(); ++i) {
    noise += f.sigma[i] * f.sigma[i] / double(kept.size());
    chi2 += std::pow(f.n.dot(pts[i] - f.mean), 2) * f.w2[i];
  }
  // Flat (the scatter along the normal within twice the noise's, the noise taken out of the
  // ratio) and two-dimensional (a tenth of the cube across at least).
  if (chi2 > 2.0 * double(kept.size())) return {};
  if (f.ev(1) < std::max(4.0 * noise, std::pow(0.1 * o.plane_radius_m, 2))) return {};
  if (std::max(0.0, f.ev(0) - noise) > o.max_planarity_ratio * f.ev(1)) return {};
  std::vector<int> out;
  for (size_t i = 0; i < kept.size(); ++i) {
    if (o.max_incidence_rad < 0.5 * M_PI &&
        std::abs(dirs[i].dot(f.n)) < std::cos(o.max_incidence_rad))
      continue;
    out.push_back(kept[i]);
  }
  if (!o.check_own_plane) return out;
  for (int h = 0; h < 2; ++h) {
    std::vector<Eigen::Vector3d> hp;
    for (int i : out) {
      if (int(rays[size_t(i)].left) == h) hp.push_back(c.p[size_t(i)]);
    }
    Eigen::Vector3d m, n;
    if (int(hp.size()) < o.min_neighbours ||
        !fitPcaPlane(hp.data(), int(hp.size()), 1.0, 1e300, &m, &n) ||
        std::abs(n.dot(f.n)) < std::cos(o.max_normal_angle_rad)) {
      return {};
    }
  }
  return out;
}

// Where each ray meets the plane of its cube's surface, fitted to the cube and its two
// neighbours along the cube's normal (the surface's whole noise band, wherever the cubes'
// faces cut it); the ray's own point where there is none. Patches are cut by these points,
// not by the measured ones: cut by the measured points, a surface near a cube's face splits
// by the sign of each point's noise, and the two passes' shares of it, of unequal noise, have
// their means pulled apart.
std::vector<Eigen::Vector3d> surfacePoints(const std::vector<OverlapRay>& rays, const Cloud& c,
                                           const std::vector<int>& eligible, double size,
                                           int threads) {
  std::vector<CubeKey> keys;
  std::vector<int> idx;
  std::vector<size_t> begin;
  groupByCube(
      eligible, size, [&](int i) { return c.p[size_t(i)]; }, &keys, &idx, &begin);
  std::vector<Eigen::Vector3d> out(rays.size(), Eigen::Vector3d::Zero());
  const auto cubePoints = [&](const CubeKey& k, std::vector<Eigen::Vector3d>* pts) {
    const auto it = std::lower_bound(keys.begin(), keys.end(), k);
    if (it == keys.end() || *it != k) return;
    const size_t j = size_t(it - keys.begin());
    for (size_t m = begin[j]; m < begin[j + 1]; ++m) pts->push_back(c.p[size_t(idx[m])]);
  };
  forChunks(keys.size(), threads, [&](size_t, size_t b, size_t e) {
    for (size_t k = b; k < e; ++k) {
      std::vector<Eigen::Vector3d> pts;
      cubePoints(keys[k], &pts);
      Eigen::Vector3d mean, n;
      bool ok = fitPcaPlane(pts.data(), int(pts.size()), 1.0, 1e300, &mean, &n);
      if (ok) {
        int axis = 0;
        for (int a = 1; a < 3; ++a) {
          if (std::abs(n(a)) > std::abs(n(axis))) axis = a;
        }
        for (int side : {-1, 1}) {
          CubeKey nb = keys[k];
          nb[size_t(axis)] += side;
          cubePoints(nb, &pts);
        }
        ok = fitPcaPlane(pts.data(), int(pts.size()), 1.0, 1e300, &mean, &n);
      }
      for (size_t m = begin[k]; m < begin[k + 1]; ++m) {
        const size_t i = size_t(idx[m]);
        out[i] = c.p[i];
        const double cos_inc = ok ? n.dot(c.dir[i]) : 0.0;
        if (std::abs(cos_inc) < 0.1) continue;
        const Eigen::Vector3d origin = c.p[i] - rays[i].range_m * c.dir[i];
        out[i] = origin + c.dir[i] * (n.dot(mean - origin) / cos_inc);
      }
    }
  });
  return out;
}

// Joins the cubes of one surface that lie behind one another along its normal (a surface
// near a cube's face, its points' surface points on either side of it by a hair): each cube
// with the next along the largest axis of its normal when their planes agree (within
// max_normal_angle_rad, offsets within half a cube). A joined patch keeps the first cube's key.
void mergeAlongNormals(const Cloud& c, double size, double max_normal_angle_rad,
                       std::vector<CubeKey>* keys, std::vector<int>* idx,
                       std::vector<size_t>* begin) {
  const size_t K = keys->size();
  std::vector<Eigen::Vector3d> mean(K), n(K);
  std::vector<char> ok(K, 0);
  for (size_t k = 0; k < K; ++k) {
    std::vector<Eigen::Vector3d> pts;
    for (size_t m = (*begin)[k]; m < (*begin)[k + 1]; ++m) pts.push_back(c.p[size_t((*idx)[m])]);
    ok[k] = fitPcaPlane(pts.data(), int(pts.size()), 1.0, 1e300, &mean[k], &n[k]);
  }
  std::vector<size_t> root(K);
  for (size_t k = 0; k < K; ++k) root[k] = k;
  const auto find = [&](size_t k) {
    while (root[k] != k) k = root[k] = root[root[k]];
    return k;
  };
  for (size_t k = 0; k < K; ++k) {
    if (!ok[k]) continue;
    int axis = 0;
    for (int a = 1; a < 3; ++a) {
      if (std::abs(n[k](a)) > std::abs(n[k](axis))) axis = a;
    }
    CubeKey next = (*keys)[k];
    next[size_t(axis)] += 1;
    const auto it = std::lower_bound(keys->begin(), keys->end(), next);
    if (it == keys->end() || *it != next) continue;
    const size_t j = size_t(it - keys->begin());
    if (!ok[j] || std::abs(n[k].dot(n[j])) < std::cos(max_normal_angle_rad) ||
        std::abs(n[k].dot(mean[j] - mean[k])) > 0.5 * size)
      continue;
    const size_t a = find(k), b = find(j);
    root[std::max(a, b)] = std::min(a, b);
  }
  std::vector<std::vector<size_t>> groups(K);
  for (size_t k = 0; k < K; ++k) groups[find(k)].push_back(k);
  std::vector<CubeKey> out_keys;
  std::vector<int> out_idx;
  std::vector<size_t> out_begin = {0};
  for (size_t g = 0; g < K; ++g) {
    if (groups[g].empty()) continue;
    for (size_t k : groups[g])
      out_idx.insert(out_idx.end(), idx->begin() + long((*begin)[k]),
                     idx->begin() + long((*begin)[k + 1]));
    out_keys.push_back((*keys)[g]);
    out_begin.push_back(out_idx.size());
  }
  *keys = std::move(out_keys);
  *idx = std::move(out_idx);
  *begin = std::move(out_begin);
}

// The patches of the covered rays within the query ranges, by cube of patch_m of their
// surfacePoints (in the cubes' key order; each cube tested on all cores in fixed chunks).
Patches searchPatches(const std::vector<OverlapRay>& rays, const Cloud& c, const OverlapOptions& oo,
                      int threads) {
  const MountingCalibrationOptions& o = oo.base;
  std::vector<int> eligible;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (c.covered[i] && rays[i].range_m >= o.min_range_m && rays[i].range_m <= o.max_range_m)
      eligible.push_back(int(i));
  }
  const std::vector<Eigen::Vector3d> surface =
      surfacePoints(rays, c, eligible, oo.patch_m, threads);
  std::vector<CubeKey> keys;
  std::vector<int> idx;
  std::vector<size_t> cube;
  groupByCube(
      eligible, oo.patch_m, [&](int i) { return surface[size_t(i)]; }, &keys, &idx, &cube);
  mergeAlongNormals(c, oo.patch_m, oo.base.max_normal_angle_rad, &keys, &idx, &cube);
  std::vector<std::vector<int>> kept(keys.size());
  forChunks(kept.size(), threads, [&](size_t, size_t b, size_t e) {
    for (size_t k = b; k < e; ++k)
      kept[k] = patchMembers(rays, c, &idx[cube[k]], cube[k + 1] - cube[k], o);
  });
  Patches out;
  out.begin.push_back(0);
  for (const auto& m : kept) {
    if (m.empty()) continue;
    out.members.insert(out.members.end(), m.begin(), m.end());
    out.begin.push_back(out.members.size());
  }
  return out;
}

// Where each ray meets the patch's plane (s), and dp/dx there: the plane's fit takes its
// in-plane coordinates from s, not from the point, whose coordinates hold its range noise's
// share along the plane, which correlates with its residual (a ray measured long lies further
// out along the plane as well as behind it) and tilts the fit towards each pass's line of
// sight. The Jacobians are s's for the same reason: the point's grow with its range (a
// rotation moves it by its range times the angle), and a Jacobian that grows with the
// residual's own noise pulls the solution.
void surfaceJacobians(const std::vector<OverlapRay>& rays, const OverlapModel& model,
                      const int* idx, size_t count, const PatchFit& f,
                      std::vector<Eigen::Vector3d>* pts, std::vector<Eigen::Vector3d>* dirs,
                      std::vector<Eigen::Vector3d>* s, std::vector<OverlapJacobian>* J) {
  s->resize(count);
  J->resize(count);
  for (size_t i = 0; i < count; ++i) {
    const size_t ray = size_t(idx[i]);
    const Eigen::Vector3d origin = (*pts)[i] - rays[ray].range_m * (*dirs)[i];
    const double cos_inc = f.n.dot((*dirs)[i]);
    const double range = std::abs(cos_inc) > 1e-3 ? f.n.dot(f.mean - origin) / cos_inc : 0.0;
    if (range > 0.0) {
      (*s)[i] = origin + (*dirs)[i] * range;
      model.jacobianAtRange(ray, range, &(*J)[i]);
    } else {
      (*s)[i] = (*pts)[i];
      model.point(ray, &(*pts)[i], &(*dirs)[i], &(*J)[i]);
    }
  }
}

// One patch's residuals into out[0..count): each point's distance from the patch's plane with
// the plane's offset and tilt eliminated (its weighted least-squares fit to the points, and to
// their Jacobians, subtracted: the Schur complement of the plane), weighted by its range noise.
// With `trim`, points beyond trim_noise_sigmas of their noise are dropped first.
void formCoveredPatch(const std::vector<OverlapRay>& rays, const OverlapModel& model,
                      const int* idx, size_t count, bool trim, const MountingCalibrationOptions& o,
                      Residual* out) {
  std::vector<Eigen::Vector3d> pts(count), dirs(count);
  std::vector<OverlapJacobian> J;
  for (size_t i = 0; i < count; ++i) model.point(size_t(idx[i]), &pts[i], &dirs[i], nullptr);
  PatchFit f;
  fitPatch(rays, idx, count, pts.data(), dirs.data(), o, &f);
  std::vector<char> keep(count, 1);
  if (trim) {
    for (size_t i = 0; i < count; ++i) {
      keep[i] = std::abs(f.n.dot(pts[i] - f.mean)) <=
                std::max(o.min_trim_m, o.trim_noise_sigmas * f.sigma[i]);
      if (!keep[i]) f.w2[i] = 0.0;
    }
    weightedPlane(&f);
  }
  // The plane's weighted fit: a = (1, u.(s - mean), v.(s - mean)), A = sum w2 a a^T, s and the
  // Jacobians as surfaceJacobians says.
  std::vector<Eigen::Vector3d> s;
  surfaceJacobians(rays, model, idx, count, f, &pts, &dirs, &s, &J);
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d ay = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, kMaxOverlapParameters> aJ = decltype(aJ)::Zero();
  std::vector<Eigen::Vector3d> a(count);
  std::vector<Eigen::Matrix<double, 1, kMaxOverlapParameters>> nJ(count);
  double t_side[2] = {0.0, 0.0}, n_side[2] = {0.0, 0.0};
  int kept = 0;
  for (size_t i = 0; i < count; ++i) {
    const Eigen::Vector3d d = s[i] - f.mean;
    a[i] = Eigen::Vector3d(1.0, f.u.dot(d), f.v.dot(d));
    nJ[i] = f.n.transpose() * J[i];
    if (!keep[i]) continue;
    ++kept;
    A += f.w2[i] * a[i] * a[i].transpose();
    ay += f.w2[i] * a[i] * f.n.dot(pts[i] - f.mean);
    aJ += f.w2[i] * a[i] * nJ[i];
    const OverlapRay& r = rays[size_t(idx[i])];
    t_side[r.left] += 1e-6 * double(r.utime - rays.front().utime);
    n_side[r.left] += 1.0;
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
  const bool solvable = kept > 3 && ldlt.info() == Eigen::Success && ldlt.rcond() > 1e-12;
  const Eigen::Vector3d cy = solvable ? Eigen::Vector3d(ldlt.solve(ay)) : Eigen::Vector3d::Zero();
  const Eigen::Matrix<double, 3, kMaxOverlapParameters> cJ =
      solvable ? decltype(aJ)(ldlt.solve(aJ)) : aJ;
  for (size_t i = 0; i < count; ++i) {
    Residual& res = out[i];
    const OverlapRay& r = rays[size_t(idx[i])];
    res.r = f.n.dot(pts[i] - f.mean) - a[i].dot(cy);
    res.J = nJ[i] - a[i].transpose() * cJ;
    res.at = f.mean.cast<float>();
    res.t_a_s = 1e-6 * double(r.utime - rays.front().utime);
    const int other = r.left ? 0 : 1;
    res.t_b_s = n_side[other] > 0 ? t_side[other] / n_side[other] : res.t_a_s;
    res.w = o.noise_weighting ? std::sqrt(f.w2[i] > 0 ? f.w2[i]
                                                      : 1.0 / (f.sigma[i] * f.sigma[i] +
                                                               o.model_sigma_m * o.model_sigma_m))
                              : 1.0;
    res.scale =
        o.noise_weighting ? std::max(o.loss_scale_sigmas, o.loss_scale_m * res.w) : o.loss_scale_m;
    res.keep = solvable && keep[i];
    res.dof = 1.0 - 3.0 / double(std::max(4, kept));
  }
}

// formCoveredPatch over the rays of the patch that the track covers at the current estimate
// (a time offset moves the ends of the track); the others' residuals dropped.
void formPatch(const std::vector<OverlapRay>& rays, const OverlapModel& model, const int* idx,
               size_t count, bool trim, const MountingCalibrationOptions& o, Residual* out) {
  std::vector<int> covered;
  std::vector<size_t> slot;
  Eigen::Vector3d p, d;
  for (size_t i = 0; i < count; ++i) {
    out[i].r = 0.0;
    out[i].w = out[i].scale = 1.0;
    out[i].J.setZero();
    out[i].keep = false;
    out[i].at.setZero();
    out[i].t_a_s = out[i].t_b_s = out[i].dof = 0.0;
    if (!model.point(size_t(idx[i]), &p, &d, nullptr)) continue;
    covered.push_back(idx[i]);
    slot.push_back(i);
  }
  if (covered.size() < 4) return;
  std::vector<Residual> part(covered.size());
  formCoveredPatch(rays, model, covered.data(), covered.size(), trim, o, part.data());
  for (size_t j = 0; j < slot.size(); ++j) out[slot[j]] = part[j];
}

// Every patch's residuals, into *out (as formResiduals).
void formPatchResiduals(const std::vector<OverlapRay>& rays, const OverlapModel& model,
                        const Patches& patches, bool trim, const MountingCalibrationOptions& o,
                        int threads, std::vector<Residual>* out) {
  out->resize(patches.members.size());
  forChunks(patches.count(), threads, [&](size_t, size_t b, size_t e) {
    for (size_t k = b; k < e; ++k) {
      const size_t at = patches.begin[k];
      formPatch(rays, model, &patches.members[at], patches.begin[k + 1] - at, trim, o, &(*out)[at]);
    }
  });
}

using Normal = Eigen::Matrix<double, kMaxOverlapParameters, kMaxOverlapParameters>;
using Gradient = Eigen::Matrix<double, kMaxOverlapParameters, 1>;

// A round's kept residuals, laid out for the reweighting: the weighted rows w J over the
// model's P parameters, the weighted residuals w r, 1 / scale^2 of each's Cauchy loss, and
// each's share of the degrees of freedom. Only the loss weights change between iterations.
struct WeightedRows {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> A;
  Eigen::VectorXd e0, inv_scale2, dof;
};

// The rows of the `kept` residuals of rs that keep is set on (alignOverlap has counted them).
WeightedRows weightedRows(const std::vector<Residual>& rs, int kept, int P) {
  const auto n = Eigen::Index(kept);
  WeightedRows w;
  w.A.resize(n, P);
  w.e0.resize(n);
  w.inv_scale2.resize(n);
  w.dof.resize(n);
  Eigen::Index i = 0;
  for (const Residual& r : rs) {
    if (!r.keep) continue;
    w.A.row(i) = r.w * r.J.head(P);
    w.e0(i) = r.w * r.r;
    w.inv_scale2(i) = 1.0 / (r.scale * r.scale);
    w.dof(i) = r.dof;
    ++i;
  }
  return w;
}

// The reweighted normal equations at the change dx. Each chunk scales its rows by the
// square roots of their loss weights and takes one symmetric rank update (a blocked
// product); the chunks' sums are reduced in order, so any thread count gives the same sums.
void normalEquations(const WeightedRows& w, const Gradient& dx, int threads, Normal* H, Gradient* g,
                     double* chi2, double* used) {
  const Eigen::Index P = w.A.cols();
  const size_t n = size_t(w.A.rows());
  const size_t chunks = (n + kChunk - 1) / kChunk;
  std::vector<Eigen::MatrixXd> Hs(chunks, Eigen::MatrixXd::Zero(P, P));
  std::vector<Eigen::VectorXd> gs(chunks);
  std::vector<double> cs(chunks, 0.0);
  std::vector<double> us(chunks, 0.0);
  const Eigen::VectorXd step = dx.head(P);
  forChunks(n, threads, [&](size_t c, size_t b, size_t e) {
    const auto rows = w.A.middleRows(Eigen::Index(b), Eigen::Index(e - b));
    const Eigen::VectorXd ei = w.e0.segment(Eigen::Index(b), rows.rows()) + rows * step;
    const Eigen::ArrayXd rho1 =  // Cauchy
        1.0 /
        (1.0 + ei.array().square() * w.inv_scale2.segment(Eigen::Index(b), rows.rows()).array());
    gs[c] = rows.transpose() * (rho1 * ei.array()).matrix();
    cs[c] = (rho1 * ei.array().square()).sum();
    us[c] = w.dof.segment(Eigen::Index(b), rows.rows()).sum();
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> scaled =
        rho1.sqrt().matrix().asDiagonal() * rows;
    Hs[c].selfadjointView<Eigen::Lower>().rankUpdate(scaled.transpose());
  });
  Eigen::MatrixXd lower = Eigen::MatrixXd::Zero(P, P);
  g->setZero();
  *chi2 = 0.0;
  *used = 0.0;
  for (size_t c = 0; c < chunks; ++c) {
    lower += Hs[c];
    g->head(P) += gs[c];
    *chi2 += cs[c];
    *used += us[c];
  }
  H->setZero();
  H->topLeftCorner(P, P) = lower.selfadjointView<Eigen::Lower>();
}

// Iteratively reweighted Gauss-Newton on the round's linear residuals; the change, within
// the bounds, and the last normal matrix.
Gradient solveRound(const std::vector<Residual>& rs, int kept, const Eigen::VectorXd& x, int P,
                    const OverlapOptions& oo, int threads, Normal* H_out, double* chi2_dof) {
  Gradient dx = Gradient::Zero();
  std::vector<int> free;
  for (int k = 0; k < P; ++k) {
    if (oo.free.empty() || oo.free[size_t(k)]) free.push_back(k);
  }
  const int F = int(free.size());
  if (F == 0) return dx;
  const WeightedRows rows = weightedRows(rs, kept, P);  // alive with rs: half as large again
  for (int it = 0; it < oo.irls_iterations; ++it) {
    Normal H;
    Gradient g;
    double chi2 = 0.0;
    double used = 0.0;
    normalEquations(rows, dx, threads, &H, &g, &chi2, &used);
    Eigen::MatrixXd Hf(F, F);
    Eigen::VectorXd gf(F);
    for (int i = 0; i < F; ++i) {
      gf(i) = g(free[size_t(i)]);
      for (int j = 0; j < F; ++j) Hf(i, j) = H(free[size_t(i)], free[size_t(j)]);
    }
    const Eigen::VectorXd step = Hf.ldlt().solve(-gf);
    Gradient next = dx;
    for (int i = 0; i < F; ++i) next(free[size_t(i)]) += step(i);
    for (int k = 0; k < P; ++k) {
      if (oo.lower.size() == P) next(k) = std::max(next(k), oo.lower(k) - x(k));
      if (oo.upper.size() == P) next(k) = std::min(next(k), oo.upper(k) - x(k));
    }
    const double moved = (next - dx).cwiseAbs().maxCoeff();
    dx = next;
    *H_out = H;
    *chi2_dof = chi2 / std::max(1.0, used - F);
    if (moved < 1e-12) break;
  }
  return dx;
}

double plainRms(const std::vector<Residual>& rs, const Gradient& dx) {
  double ss = 0.0;
  int n = 0;
  for (const Residual& r : rs) {
    if (!r.keep) continue;
    const double e = r.r + r.J.dot(dx.transpose());
    ss += e * e;
    ++n;
  }
  return n > 0 ? std::sqrt(ss / n) : 0.0;
}

// The covariance of the free parameters: chi2/dof times the inverse normal matrix.
Eigen::MatrixXd covariance(const Normal& H, double chi2_dof, int P, const OverlapOptions& oo) {
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(P, P);
  std::vector<int> free;
  for (int k = 0; k < P; ++k) {
    if (oo.free.empty() || oo.free[size_t(k)]) free.push_back(k);
  }
  const int F = int(free.size());
  if (F == 0) return cov;
  Eigen::MatrixXd Hf(F, F);
  for (int i = 0; i < F; ++i) {
    for (int j = 0; j < F; ++j) Hf(i, j) = H(free[size_t(i)], free[size_t(j)]);
  }
  const Eigen::MatrixXd inv = Hf.ldlt().solve(Eigen::MatrixXd::Identity(F, F)) * chi2_dof;
  for (int i = 0; i < F; ++i) {
    for (int j = 0; j < F; ++j) cov(free[size_t(i)], free[size_t(j)]) = inv(i, j);
  }
  return cov;
}

}  // namespace

bool fitPcaPlane(const Eigen::Vector3d* pts, int count, double max_ratio, double max_variance,
                 Eigen::Vector3d* mean, Eigen::Vector3d* normal) {
  if (count < 3) return false;
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (int i = 0; i < count; ++i) m += pts[i];
  m /= double(count);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < count; ++i) cov += (pts[i] - m) * (pts[i] - m).transpose();
  cov /= double(count);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  const Eigen::Vector3d ev = es.eigenvalues();
  if (!(ev(0) <= max_ratio * ev(1)) || !(ev(0) <= max_variance)) return false;
  Eigen::Vector3d n = es.eigenvectors().col(0);
  int big = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::abs(n(i)) > std::abs(n(big))) big = i;
  }
  if (n(big) < 0) n = -n;
  *mean = m;
  *normal = n;
  return true;
}

namespace {

// Whether valid ray i of `scan` lies at a depth edge: a valid neighbour's range differs from
// its own by more than the noise of the two explains.
bool atDepthEdge(const Scan2D& scan, size_t i, const MountingCalibrationOptions& o) {
  const double r = scan.ranges_m[i];
  for (const size_t j : {i - 1, i + 1}) {
    if (j >= scan.ranges_m.size() || !scan.validRange(j)) continue;
    const double q = scan.ranges_m[j];
    const double sigma = M_SQRT2 * o.range_noise_fraction * std::max(r, q);
    if (std::abs(q - r) > std::max(o.min_edge_jump_m, o.edge_jump_sigmas * sigma)) return true;
  }
  return false;
}

}  // namespace

std::vector<OverlapRay> overlapRays(const std::vector<Scan2D>& scans, const Eigen::Vector3d& rpy,
                                    const MountingCalibrationOptions& o) {
  std::vector<OverlapRay> rays;
  const Eigen::Matrix3d R_nom = rotationXYZ(rpy.x(), rpy.y(), rpy.z());
  for (const Scan2D& scan : scans) {
    for (size_t i = 0; i < scan.ranges_m.size(); i += size_t(std::max(1, o.ray_stride))) {
      if (!scan.validRange(i) || atDepthEdge(scan, i, o)) continue;
      const double r = scan.ranges_m[i];
      const double a = scan.rayAngle(i);
      rays.push_back(
          {R_nom * rotating::pointInLidar(r, a), scan.rayUtime(i), std::sin(a) > 0.0, r});
    }
  }
  return rays;
}

// A residual's cluster: its cube of cluster_m (residuals that share the other pass's planes,
// or a wall's unevenness, err together) and, with cluster_s, the pair of time windows of its
// query and its neighbours (residuals between the same two stretches of the drive share the
// track's error between them: the encoders' noise, a slip, the gyro's drift).
using ClusterKey = std::array<int64_t, 5>;
enum class Clustering { kSpace, kTime, kBoth };
ClusterKey clusterOf(const Residual& r, const OverlapOptions& oo, Clustering c) {
  ClusterKey key = {0, 0, 0, 0, 0};
  if (c != Clustering::kTime) {
    for (int k = 0; k < 3; ++k) key[size_t(k)] = int64_t(std::floor(r.at(k) / oo.cluster_m));
  }
  if (c != Clustering::kSpace) {
    const int64_t a = int64_t(std::floor(r.t_a_s / oo.cluster_s));
    const int64_t b = int64_t(std::floor(r.t_b_s / oo.cluster_s));
    key[3] = std::min(a, b);  // either way round: the same two stretches
    key[4] = std::max(a, b);
  }
  return key;
}

// The sum over clusters of each cluster's gradient outer product (free parameters), scaled
// by C / (C - 1); false with too few clusters for it.
bool clusterMeat(const std::vector<Residual>& rs, const Gradient& dx, const std::vector<int>& free,
                 const OverlapOptions& oo, Clustering c, Eigen::MatrixXd* M) {
  std::map<ClusterKey, Gradient> sums;
  for (const Residual& r : rs) {
    if (!r.keep) continue;
    const double ei = r.w * (r.r + r.J.dot(dx.transpose()));
    const double rho1 = 1.0 / (1.0 + ei * ei / (r.scale * r.scale));
    auto [it, inserted] = sums.try_emplace(clusterOf(r, oo, c), Gradient::Zero());
    it->second.noalias() += rho1 * ei * r.w * r.J.transpose();
  }
  const int F = int(free.size()), C = int(sums.size());
  if (C <= 10 * F) return false;
  *M = Eigen::MatrixXd::Zero(F, F);
  for (const auto& [key, g] : sums) {
    Eigen::VectorXd gf(F);
    for (int i = 0; i < F; ++i) gf(i) = g(free[size_t(i)]);
    M->noalias() += gf * gf.transpose();
  }
  *M *= double(C) / double(C - 1);
  return true;
}

// The cluster-robust (sandwich) covariance H^-1 M H^-1 of the free parameters: M over cubes of
// cluster_m and, with cluster_s, two-way (Cameron, Gelbach and Miller 2011: the cubes' M plus
// the time pairs' less their intersection's; where that is not positive, the sum of the two).
// chi2 / H^-1 counts correlated residuals as independent. Never below `classic` on the
// diagonal (scaled to it, correlations kept).
Eigen::MatrixXd clusteredCovariance(const std::vector<Residual>& rs, const Gradient& dx,
                                    const Normal& H, const Eigen::MatrixXd& classic, int P,
                                    const OverlapOptions& oo) {
  std::vector<int> free;
  for (int k = 0; k < P; ++k) {
    if (oo.free.empty() || oo.free[size_t(k)]) free.push_back(k);
  }
  const int F = int(free.size());
  Eigen::MatrixXd M;
  if (F == 0 || !clusterMeat(rs, dx, free, oo, Clustering::kSpace, &M)) return classic;
  Eigen::MatrixXd Hf(F, F);
  for (int i = 0; i < F; ++i) {
    for (int j = 0; j < F; ++j) Hf(i, j) = H(free[size_t(i)], free[size_t(j)]);
  }
  const Eigen::MatrixXd Hinv = Hf.ldlt().solve(Eigen::MatrixXd::Identity(F, F));
  Eigen::MatrixXd Mt, Mb;
  if (oo.cluster_s > 0 && clusterMeat(rs, dx, free, oo, Clustering::kTime, &Mt) &&
      clusterMeat(rs, dx, free, oo, Clustering::kBoth, &Mb)) {
    const Eigen::MatrixXd two_way = M + Mt - Mb;
    const Eigen::MatrixXd S = Hinv * two_way * Hinv;
    M = S.diagonal().minCoeff() > 0 ? two_way : Eigen::MatrixXd(M + Mt);
  }
  Eigen::VectorXd at_least(F);
  for (int i = 0; i < F; ++i) at_least(i) = classic(free[size_t(i)], free[size_t(i)]);
  const Eigen::MatrixXd S = widenedTo(Hinv * M * Hinv, at_least);
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(P, P);
  for (int i = 0; i < F; ++i) {
    for (int j = 0; j < F; ++j) cov(free[size_t(i)], free[size_t(j)]) = S(i, j);
  }
  return cov;
}

Eigen::MatrixXd widenedTo(const Eigen::MatrixXd& cov, const Eigen::VectorXd& variance) {
  eigen_assert(cov.rows() == cov.cols() && variance.size() == cov.rows());
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(cov.rows());
  for (Eigen::Index i = 0; i < cov.rows(); ++i) {
    if (cov(i, i) > 0.0 && std::isfinite(variance(i)) && cov(i, i) < variance(i))
      scale(i) = std::sqrt(variance(i) / cov(i, i));
  }
  return scale.asDiagonal() * cov * scale.asDiagonal();
}

OverlapResult alignOverlap(const std::vector<OverlapRay>& rays, OverlapModel& model,
                           const Eigen::VectorXd& x0, const OverlapOptions& oo) {
  const MountingCalibrationOptions& o = oo.base;
  const int P = model.parameterCount();
  const int threads = threadCount(oo.threads);
  OverlapResult res;
  res.x = x0;
  Cloud cloud;
  std::vector<Correspondence> corrs;
  PlaneGroups plane_groups;  // fixed from a ray's first search as a query on
  Patches patches;
  double change = 1e300;
  Normal H = Normal::Zero();
  double chi2_dof = 0.0;
  std::vector<Residual> rs;    // this round's residuals
  std::vector<Residual> last;  // the last round's residuals and change
  Gradient last_dx = Gradient::Zero();
  for (int round = 0; round < o.max_outer_iterations; ++round) {
    if (oo.progress) oo.progress(double(round) / o.max_outer_iterations);
    model.linearise(res.x);
    computePoints(rays, model, threads, &cloud);
    if (round <= 1 || change > oo.research_change) {
      if (std::count(cloud.covered.begin(), cloud.covered.end(), 1) < 100) {
        res.reason = "the pose track covers too few lidar rays";
        return res;
      }
      if (oo.patch_residuals) {
        patches = searchPatches(rays, cloud, oo, threads);
      } else {
        buildTrees(rays, oo.plane_voxel_m, &cloud);
        corrs = search(rays, cloud, oo, threads, &plane_groups, &res.local_planes);
      }
      ++res.searches;
    }
    if (oo.patch_residuals) {
      formPatchResiduals(rays, model, patches, round > 0, o, threads, &rs);
    } else {
      formResiduals(rays, model, corrs, round > 0, o, threads, &rs);
    }
    const int kept =
        int(std::count_if(rs.begin(), rs.end(), [](const Residual& r) { return r.keep; }));
    if (kept < o.min_correspondences) {
      res.reason = "too few overlapping points of the two passes (" + std::to_string(kept) + " < " +
                   std::to_string(o.min_correspondences) + ")";
      return res;
    }
    if (round == 0) res.residual_before_m = plainRms(rs, Gradient::Zero());
    const Gradient dx = solveRound(rs, kept, res.x, P, oo, threads, &H, &chi2_dof);
    res.residual_after_m = plainRms(rs, dx);
    res.correspondences = kept;
    res.rounds = round + 1;
    change = 0.0;
    for (int k = 0; k < P; ++k) {
      const double scale = k == MobileOverlapModel::kTimeOffset ? 1e-2 : 1.0;
      change = std::max(change, std::abs(dx(k)) * scale);
    }
    res.x += dx.head(P);
    if (oo.cluster_m > 0) {
      std::swap(last, rs);  // rs keeps the storage of the round before for the next
      last_dx = dx;
    }
    if (round >= 1 && change < o.convergence_rad) break;
  }
  res.covariance = covariance(H, chi2_dof, P, oo);
  if (oo.cluster_m > 0)
    res.covariance = clusteredCovariance(last, last_dx, H, res.covariance, P, oo);
  res.information = H.topLeftCorner(P, P) / std::max(1e-300, chi2_dof);
  res.chi2_per_dof = chi2_dof;
  res.ok = true;
  if (oo.progress) oo.progress(1.0);
  return res;
}

// ------------------------------------------------------------------------- rig B's model

MobileOverlapModel::MobileOverlapModel(const std::vector<OverlapRay>& rays, const PoseTrack& track,
                                       const Eigen::Vector3d& t_BL_m,
                                       std::vector<Sensitivity> sensitivities)
    : rays_(rays), track_(&track), sens_(std::move(sensitivities)), t_BL_(t_BL_m) {
  if (!rays.empty()) t_mid_us_ = 0.5 * (double(rays.front().utime) + double(rays.back().utime));
}

void MobileOverlapModel::setTrack(const PoseTrack& track, std::vector<Sensitivity> sensitivities) {
  track_ = &track;
  sens_ = std::move(sensitivities);
}

void MobileOverlapModel::linearise(const Eigen::VectorXd& x) {
  x_ = x;
  const double g = x(kGamma), b = x(kBeta), a = x(kAlpha);
  const Eigen::Matrix3d Rx = rotationXYZ(g, 0, 0), Ry = rotationXYZ(0, b, 0),
                        Rz = rotationXYZ(0, 0, a);
  Eigen::Matrix3d Kx, Ky, Kz;  // generators: d/dt R(t) = K R(t)
  Kx << 0, 0, 0, 0, 0, -1, 0, 1, 0;
  Ky << 0, 0, 1, 0, 0, 0, -1, 0, 0;
  Kz << 0, -1, 0, 1, 0, 0, 0, 0, 0;
  R_ = Rz * Ry * Rx;
  dR_[0] = Rz * Ry * Kx * Rx;
  dR_[1] = Rz * Ky * Ry * Rx;
  dR_[2] = Kz * Rz * Ry * Rx;
  // Poses at ray time + dt and their rates (central differences over 20 ms).
  constexpr double kHalfStepUs = 10'000.0;
  const double dt_us = x(kTimeOffset) * 1e6;
  const size_t S = sens_.size();
  poses_.assign(rays_.size(), RayPose{0, 0, 0, 0, 0, 0, false});
  dpose_.assign(rays_.size() * 3 * S, 0.0);
  for (size_t i = 0; i < rays_.size(); ++i) {
    const double t = double(rays_[i].utime) + dt_us;
    const auto at = [&](const PoseTrack& tr, double tu) {
      return tr.at(static_cast<int64_t>(std::llround(tu)));
    };
    const auto p = at(*track_, t);
    if (!p) continue;
    auto lo = at(*track_, t - kHalfStepUs), hi = at(*track_, t + kHalfStepUs);
    double span_us = 2 * kHalfStepUs;
    if (!lo) {
      lo = p;
      span_us -= kHalfStepUs;
    }
    if (!hi) {
      hi = p;
      span_us -= kHalfStepUs;
    }
    RayPose& r = poses_[i];
    r = {p->x_m, p->y_m, p->theta_rad, 0, 0, 0, true};
    if (span_us > 0) {
      const double s = span_us * 1e-6;
      r.vx = (hi->x_m - lo->x_m) / s;
      r.vy = (hi->y_m - lo->y_m) / s;
      r.vth = wrapAngle(hi->theta_rad - lo->theta_rad) / s;
    }
    for (size_t k = 0; k < S; ++k) {
      const auto q = at(*sens_[k].track, t);
      if (!q) {
        r.covered = false;
        break;
      }
      double* d = &dpose_[(i * S + k) * 3];
      d[0] = (q->x_m - p->x_m) / sens_[k].step;
      d[1] = (q->y_m - p->y_m) / sens_[k].step;
      d[2] = wrapAngle(q->theta_rad - p->theta_rad) / sens_[k].step;
    }
  }
}

bool MobileOverlapModel::point(size_t i, Eigen::Vector3d* p, Eigen::Vector3d* direction,
                               OverlapJacobian* J) const {
  return scaledPoint(i, 1.0, p, direction, J);
}

bool MobileOverlapModel::jacobianAtRange(size_t i, double range_m, OverlapJacobian* J) const {
  Eigen::Vector3d p, d;
  return scaledPoint(i, range_m / std::max(1e-9, rays_[i].range_m), &p, &d, J);
}

bool MobileOverlapModel::scaledPoint(size_t i, double scale, Eigen::Vector3d* p,
                                     Eigen::Vector3d* direction, OverlapJacobian* J) const {
  const RayPose& P = poses_[i];
  if (!P.covered) return false;
  const OverlapRay& ray = rays_[i];
  const Eigen::Vector3d q = scale * ray.q;
  const size_t S = sens_.size();
  // The odometry parameters' entries of x are changes from the track's parameters.
  double px = P.x, py = P.y, th = P.th;
  for (size_t k = 0; k < S; ++k) {
    const double* d = &dpose_[(i * S + k) * 3];
    const double xk = x_(kFirstOdometry + int(k));
    px += d[0] * xk;
    py += d[1] * xk;
    th += d[2] * xk;
  }
  const Eigen::Vector3d lever(x_(kLeverX), x_(kLeverY), x_(kLeverZ));
  const Eigen::Vector3d rq = R_ * q;
  const Eigen::Vector3d b = rq + t_BL_ + lever;
  const double c = std::cos(th), s = std::sin(th);
  const double tau = (double(ray.utime) - t_mid_us_) * 1e-6;
  const Eigen::Vector3d rb(c * b.x() - s * b.y(), s * b.x() + c * b.y(), b.z());
  *p = Eigen::Vector3d(px, py, 0.0) + rb -
       Eigen::Vector3d(x_(kDriftX) * tau, x_(kDriftY) * tau, 0.0);
  if (direction) {
    const Eigen::Vector3d d(c * rq.x() - s * rq.y(), s * rq.x() + c * rq.y(), rq.z());
    *direction = d / std::max(1e-9, d.norm());
  }
  if (!J) return true;
  J->setZero();
  const auto rotZ = [&](const Eigen::Vector3d& v) {
    return Eigen::Vector3d(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
  };
  for (int k = 0; k < 3; ++k) J->col(kGamma + k) = rotZ(dR_[k] * q);
  const Eigen::Vector3d dth(-rb.y(), rb.x(), 0.0);  // d p / d theta
  J->col(kTimeOffset) = Eigen::Vector3d(P.vx, P.vy, 0.0) + dth * P.vth;
  J->col(kDriftX) = Eigen::Vector3d(-tau, 0.0, 0.0);
  J->col(kDriftY) = Eigen::Vector3d(0.0, -tau, 0.0);
  for (int k = 0; k < 3; ++k) J->col(kLeverX + k) = rotZ(Eigen::Vector3d::Unit(k));
  for (size_t k = 0; k < S; ++k) {
    const double* d = &dpose_[(i * S + k) * 3];
    J->col(kFirstOdometry + int(k)) = Eigen::Vector3d(d[0], d[1], 0.0) + dth * d[2];
  }
  return true;
}

}  // namespace sweepmap
