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

// The centroids of `pts` per cube of `size`, in the order of the cubes' keys.
std::vector<Eigen::Vector3d> voxelCentroids(const std::vector<Eigen::Vector3d>& pts, double size) {
  std::vector<std::pair<std::array<int64_t, 3>, int>> keys(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    keys[i] = {{int64_t(std::floor(pts[i].x() / size)), int64_t(std::floor(pts[i].y() / size)),
                int64_t(std::floor(pts[i].z() / size))},
               int(i)};
  }
  std::sort(keys.begin(), keys.end());
  std::vector<Eigen::Vector3d> out;
  for (size_t i = 0; i < keys.size();) {
    size_t j = i;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (; j < keys.size() && keys[j].first == keys[i].first; ++j)
      sum += pts[size_t(keys[j].second)];
    out.push_back(sum / double(j - i));
    i = j;
  }
  return out;
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

// Query a's correspondence, as the reference solver's planeResidual decides it: the other
// pass's local plane flat, the query's own half seeing the same plane, not grazing, the query
// over the middle of the patch.
// The range a ray from `origin` along `dir` meets the plane (normal n through m) at.
double predictedRange(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                      const Eigen::Vector3d& n, const Eigen::Vector3d& m) {
  return std::abs(n.dot(m - origin)) / std::max(1e-9, std::abs(n.dot(dir)));
}

// The plane of a patch of voxel centroids, if flat to within the range noise of the query's ray
// (at most along the normal) plus a millimetre. The noise is that of the range the plane
// predicts for the ray, not of the range measured: a limit from the measured range would pass
// the queries measured long more often than those measured short, and a noise-weighted one
// weigh them less (together 0.1 % of every range, taken up as the wheels' scale).
bool flatPatch(const Eigen::Vector3d* patch, int count, const Eigen::Vector3d& origin,
               const Eigen::Vector3d& dir, const MountingCalibrationOptions& o,
               Eigen::Vector3d* mean, Eigen::Vector3d* n) {
  if (count < o.min_neighbours ||
      !fitPcaPlane(patch, count, o.max_planarity_ratio, 1e300, mean, n)) {
    return false;
  }
  const double sigma = o.range_noise_fraction * predictedRange(origin, dir, *n, *mean);
  double var = 0.0;
  for (int i = 0; i < count; ++i) var += std::pow(n->dot(patch[i] - *mean), 2);
  return var / count <= 2.0 * sigma * sigma + 1e-6;
}

// The local planes at query a from the voxel centroids: the other pass's (its normal and
// mean), and the one the query's own half sees there, which must agree (the query lies on that
// surface, not on another one near an edge). False if either is not flat or they disagree.
bool localPlane(const OverlapRay& ra, const Cloud& c, size_t a, const MountingCalibrationOptions& o,
                Eigen::Vector3d* n, Eigen::Vector3d* mean) {
  const Eigen::Vector3d& pa = c.p[a];
  const Eigen::Vector3d origin = pa - ra.range_m * c.dir[a];
  Eigen::Vector3d patch[64];
  const int n_patch = voxelsNear(c, ra.left ? 0 : 1, pa, o.plane_radius_m, patch);
  if (!flatPatch(patch, n_patch, origin, c.dir[a], o, mean, n)) return false;
  if (!o.check_own_plane) return true;
  Eigen::Vector3d own_n, own_mean;
  const int n_own = voxelsNear(c, ra.left ? 1 : 0, pa, o.plane_radius_m, patch);
  return flatPatch(patch, n_own, origin, c.dir[a], o, &own_mean, &own_n) &&
         std::abs(own_n.dot(*n)) >= std::cos(o.max_normal_angle_rad);
}

// Query a's correspondence, as the reference solver's planeResidual decides it: flat local
// planes that agree (localPlane), the other pass's points nearest within the plane (k nearest
// of its half, at least min_pass_gap_s away), not grazing, the query over the middle of the
// patch.
bool findCorrespondence(const std::vector<OverlapRay>& rays, const Cloud& c, int a,
                        const OverlapOptions& oo, Correspondence* out) {
  const MountingCalibrationOptions& o = oo.base;
  const OverlapRay& ra = rays[size_t(a)];
  const Eigen::Vector3d& pa = c.p[size_t(a)];
  Eigen::Vector3d n, plane_mean;
  if (!localPlane(ra, c, size_t(a), o, &n, &plane_mean)) return false;
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

// Every query_stride-th covered ray within the query ranges, with its correspondence.
std::vector<Correspondence> search(const std::vector<OverlapRay>& rays, const Cloud& c,
                                   const OverlapOptions& oo, int threads) {
  const MountingCalibrationOptions& o = oo.base;
  std::vector<int> queries;
  size_t k = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!c.covered[i]) continue;
    if (k++ % size_t(std::max(1, o.query_stride)) != 0) continue;
    if (rays[i].range_m < o.min_range_m || rays[i].range_m > o.max_range_m) continue;
    queries.push_back(int(i));
  }
  std::vector<std::vector<Correspondence>> parts((queries.size() + kChunk - 1) / kChunk);
  forChunks(queries.size(), threads, [&](size_t chunk, size_t b, size_t e) {
    for (size_t q = b; q < e; ++q) {
      Correspondence corr;
      if (findCorrespondence(rays, c, queries[q], oo, &corr)) parts[chunk].push_back(corr);
    }
  });
  std::vector<Correspondence> all;
  for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
  return all;
}

// One residual, linear in the parameter change: w (r + J dx), Cauchy loss at `scale`.
struct Residual {
  double r, w, scale;
  Eigen::Matrix<double, 1, kMaxOverlapParameters> J;
  bool keep;
  Eigen::Vector3f at;   // the query's world point (its cluster for the sandwich covariance)
  double t_a_s, t_b_s;  // the query's and its neighbours' (mean) times [s], likewise
};

Residual formResidual(const std::vector<OverlapRay>& rays, const OverlapModel& model,
                      const Correspondence& corr, const MountingCalibrationOptions& o) {
  Residual res;
  Eigen::Vector3d pa, da, pb, db, mean = Eigen::Vector3d::Zero();
  OverlapJacobian Ja, Jb, Jmean = OverlapJacobian::Zero();
  model.point(size_t(corr.a), &pa, &da, &Ja);
  // The range noise along the normal of a ray from its origin: that of the range the
  // neighbours' plane predicts for it (flatPatch says why not the measured one).
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
  return res;
}

std::vector<Residual> formResiduals(const std::vector<OverlapRay>& rays, const OverlapModel& model,
                                    const std::vector<Correspondence>& corrs, bool trim,
                                    const MountingCalibrationOptions& o, int threads) {
  std::vector<Residual> out(corrs.size());
  forChunks(corrs.size(), threads, [&](size_t, size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      out[i] = formResidual(rays, model, corrs[i], o);
      out[i].keep = !trim || std::abs(out[i].r) <= corrs[i].trim_m;
    }
  });
  return out;
}

using Normal = Eigen::Matrix<double, kMaxOverlapParameters, kMaxOverlapParameters>;
using Gradient = Eigen::Matrix<double, kMaxOverlapParameters, 1>;

// The reweighted normal equations at the change dx (chunk sums reduced in order).
void normalEquations(const std::vector<Residual>& rs, const Gradient& dx, int threads, Normal* H,
                     Gradient* g, double* chi2, int* used) {
  const size_t chunks = (rs.size() + kChunk - 1) / kChunk;
  std::vector<Normal> Hs(chunks, Normal::Zero());
  std::vector<Gradient> gs(chunks, Gradient::Zero());
  std::vector<double> cs(chunks, 0.0);
  std::vector<int> us(chunks, 0);
  forChunks(rs.size(), threads, [&](size_t c, size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      const Residual& r = rs[i];
      if (!r.keep) continue;
      const double ei = r.w * (r.r + r.J.dot(dx.transpose()));
      const double rho1 = 1.0 / (1.0 + ei * ei / (r.scale * r.scale));  // Cauchy
      const Eigen::Matrix<double, 1, kMaxOverlapParameters> wj = r.w * r.J;
      Hs[c].noalias() += rho1 * wj.transpose() * wj;
      gs[c].noalias() += rho1 * ei * wj.transpose();
      cs[c] += rho1 * ei * ei;
      ++us[c];
    }
  });
  H->setZero();
  g->setZero();
  *chi2 = 0.0;
  *used = 0;
  for (size_t c = 0; c < chunks; ++c) {
    *H += Hs[c];
    *g += gs[c];
    *chi2 += cs[c];
    *used += us[c];
  }
}

// Iteratively reweighted Gauss-Newton on the round's linear residuals; the change, within
// the bounds, and the last normal matrix.
Gradient solveRound(const std::vector<Residual>& rs, const Eigen::VectorXd& x, int P,
                    const OverlapOptions& oo, int threads, Normal* H_out, double* chi2_dof) {
  Gradient dx = Gradient::Zero();
  std::vector<int> free;
  for (int k = 0; k < P; ++k) {
    if (oo.free.empty() || oo.free[size_t(k)]) free.push_back(k);
  }
  const int F = int(free.size());
  for (int it = 0; it < oo.irls_iterations && F > 0; ++it) {
    Normal H;
    Gradient g;
    double chi2 = 0.0;
    int used = 0;
    normalEquations(rs, dx, threads, &H, &g, &chi2, &used);
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
    *chi2_dof = chi2 / std::max(1, used - F);
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

std::vector<OverlapRay> overlapRays(const std::vector<Scan2D>& scans, const Eigen::Vector3d& rpy,
                                    int stride) {
  std::vector<OverlapRay> rays;
  const Eigen::Matrix3d R_nom = rotationXYZ(rpy.x(), rpy.y(), rpy.z());
  for (const Scan2D& scan : scans) {
    for (size_t i = 0; i < scan.ranges_m.size(); i += size_t(std::max(1, stride))) {
      const double r = scan.ranges_m[i];
      if (r == 0.0 || !(r >= scan.range_min_m && r <= scan.range_max_m)) continue;
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
  Eigen::MatrixXd S = Hinv * M * Hinv;
  Eigen::VectorXd scale(F);
  for (int i = 0; i < F; ++i) {
    const double c = classic(free[size_t(i)], free[size_t(i)]);
    scale(i) = S(i, i) > 0 && S(i, i) < c ? std::sqrt(c / S(i, i)) : 1.0;
  }
  S = scale.asDiagonal() * S * scale.asDiagonal();
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(P, P);
  for (int i = 0; i < F; ++i) {
    for (int j = 0; j < F; ++j) cov(free[size_t(i)], free[size_t(j)]) = S(i, j);
  }
  return cov;
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
  double change = 1e300;
  Normal H = Normal::Zero();
  double chi2_dof = 0.0;
  std::vector<Residual> last;  // the last round's residuals and change
  Gradient last_dx = Gradient::Zero();
  for (int round = 0; round < o.max_outer_iterations; ++round) {
    if (oo.progress) oo.progress(double(round) / o.max_outer_iterations);
    model.linearise(res.x);
    computePoints(rays, model, threads, &cloud);
    if (round <= 1 || change > oo.research_change) {
      buildTrees(rays, oo.plane_voxel_m, &cloud);
      if (cloud.half_index[0].size() + cloud.half_index[1].size() < 100) {
        res.reason = "the pose track covers too few lidar rays";
        return res;
      }
      corrs = search(rays, cloud, oo, threads);
      ++res.searches;
    }
    const std::vector<Residual> rs = formResiduals(rays, model, corrs, round > 0, o, threads);
    const int kept =
        int(std::count_if(rs.begin(), rs.end(), [](const Residual& r) { return r.keep; }));
    if (kept < o.min_correspondences) {
      res.reason = "too few overlapping points of the two passes (" + std::to_string(kept) + " < " +
                   std::to_string(o.min_correspondences) + ")";
      return res;
    }
    if (round == 0) res.residual_before_m = plainRms(rs, Gradient::Zero());
    const Gradient dx = solveRound(rs, res.x, P, oo, threads, &H, &chi2_dof);
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
      last = rs;
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
  const RayPose& P = poses_[i];
  if (!P.covered) return false;
  const OverlapRay& ray = rays_[i];
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
  const Eigen::Vector3d rq = R_ * ray.q;
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
  for (int k = 0; k < 3; ++k) J->col(kGamma + k) = rotZ(dR_[k] * ray.q);
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
