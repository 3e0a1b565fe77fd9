// The fast overlap alignment (calib/overlap_alignment.hpp) on a synthetic box room seen from
// two places: its residual forms against many noise draws.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <random>
#include <vector>

#include "calib/overlap_alignment.hpp"

namespace sweepmap {
namespace {

// Two passes' points of a room, the second (the left half) shifted by the parameters.
class ShiftModel : public OverlapModel {
 public:
  ShiftModel(const std::vector<OverlapRay>& rays, std::vector<Eigen::Vector3d> origins)
      : rays_(rays), origins_(std::move(origins)) {}
  int parameterCount() const override { return 3; }
  void linearise(const Eigen::VectorXd& x) override { x_ = x; }
  bool point(size_t i, Eigen::Vector3d* p, Eigen::Vector3d* direction,
             OverlapJacobian* J) const override {
    const bool moved = rays_[i].left;
    *p = rays_[i].q + (moved ? Eigen::Vector3d(x_.head<3>()) : Eigen::Vector3d::Zero());
    if (direction) *direction = (rays_[i].q - origins_[moved]).normalized();
    if (J) {
      J->setZero();
      if (moved) J->leftCols<3>().setIdentity();
    }
    return true;
  }

 private:
  const std::vector<OverlapRay>& rays_;
  std::vector<Eigen::Vector3d> origins_;
  Eigen::VectorXd x_ = Eigen::VectorXd::Zero(3);
};

// The range along d from o to the inside of the box [-1.5, 1.5] x [-1, 1] x [0, 2]: its
// walls on the faces of the 0.25 m cubes, where the patches' cut is most tempted by noise.
double rangeInBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Vector3d lo(-1.5, -1.0, 0.0), hi(1.5, 1.0, 2.0);
  double t = 1e300;
  for (int k = 0; k < 3; ++k) {
    if (d(k) > 1e-9) t = std::min(t, (hi(k) - o(k)) / d(k));
    if (d(k) < -1e-9) t = std::min(t, (lo(k) - o(k)) / d(k));
  }
  return t;
}

// Pass `left` from origin o: az x el rays over the sphere (the poles left out), each range
// with `fraction` noise; the left pass 10 s after the right.
void scan(const Eigen::Vector3d& o, int az, int el, bool left, double fraction, std::mt19937* rng,
          std::vector<OverlapRay>* rays) {
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int j = 0; j < el; ++j) {
    const double e = -1.3 + 2.6 * (j + 0.5) / el;
    for (int i = 0; i < az; ++i) {
      const double a = 2.0 * M_PI * (i + 0.5) / az;
      const Eigen::Vector3d d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      const double r = rangeInBox(o, d) * (1.0 + fraction * noise(*rng));
      rays->push_back({o + r * d, left ? 10'000'000 : 0, left, r});
    }
  }
}

struct Draws {
  double mean_z2 = 0.0;  // of the estimates' errors over their sigmas, over parameters and draws
  double rms_error_m = 0.0;
};

// The estimated shift of the sparse second pass (truly none) over `draws` noise draws.
Draws shiftDraws(bool patches, int draws) {
  Draws out;
  const std::vector<Eigen::Vector3d> origins = {{-0.4, 0.1, 0.8}, {0.5, -0.2, 1.1}};
  for (int d = 0; d < draws; ++d) {
    std::mt19937 rng(1000 + d);
    std::vector<OverlapRay> rays;
    scan(origins[0], 720, 120, false, 0.01, &rng, &rays);
    scan(origins[1], 180, 30, true, 0.01, &rng, &rays);
    ShiftModel model(rays, origins);
    OverlapOptions oo;
    oo.patch_residuals = patches;
    oo.base.max_incidence_rad = 1.2;
    const OverlapResult r = alignOverlap(rays, model, Eigen::VectorXd::Zero(3), oo);
    EXPECT_TRUE(r.ok) << r.reason;
    for (int k = 0; k < 3; ++k) {
      out.mean_z2 += r.x(k) * r.x(k) / r.covariance(k, k) / (3.0 * draws);
      out.rms_error_m += r.x(k) * r.x(k) / (3.0 * draws);
    }
  }
  out.rms_error_m = std::sqrt(out.rms_error_m);
  return out;
}

// The second pass is a quarter as dense as the first: point-to-plane compares each of the
// dense pass's queries with the plane of its 12 nearest sparse points, so each sparse point's
// noise enters many residuals that its covariance (chi2 times the inverse normal matrix)
// counts as independent. Patches give every point one residual against a plane both passes
// share, the plane eliminated: the spread of the estimates over noise draws is the sigma
// they report, and smaller than point-to-plane's. (Measured: mean z^2 31 against 1.7, RMS
// error 0.68 against 0.40 mm; E z^2 = 1 for an honest sigma, the bound allows for 36 draws
// and what the patches' cut at the room's edges leaves.)
TEST(OverlapAlignment, PatchResidualsCountEachPointsNoiseOnceAndTheirSigmaIsHonest) {
  const Draws point_to_plane = shiftDraws(false, 12), patches = shiftDraws(true, 12);
  EXPECT_GT(point_to_plane.mean_z2, 10.0);
  EXPECT_LT(patches.mean_z2, 2.5);
  EXPECT_LT(patches.rms_error_m, point_to_plane.rms_error_m);
}

// Patches are searched and their residuals formed on all cores in fixed chunks, reduced in
// chunk order: the same result, to the bit, on any number of threads.
TEST(OverlapAlignment, PatchResidualsAreTheSameOnAnyNumberOfThreads) {
  const std::vector<Eigen::Vector3d> origins = {{-0.4, 0.1, 0.8}, {0.5, -0.2, 1.1}};
  std::mt19937 rng(7);
  std::vector<OverlapRay> rays;
  scan(origins[0], 720, 120, false, 0.01, &rng, &rays);
  scan(origins[1], 180, 30, true, 0.01, &rng, &rays);
  Eigen::VectorXd x[3];
  for (int t = 1; t <= 3; ++t) {
    ShiftModel model(rays, origins);
    OverlapOptions oo;
    oo.patch_residuals = true;
    oo.patch_m = 0.1;  // more patches than one chunk holds
    oo.threads = t;
    oo.cluster_m = 0.5;
    const OverlapResult r = alignOverlap(rays, model, Eigen::VectorXd::Zero(3), oo);
    ASSERT_TRUE(r.ok) << r.reason;
    x[t - 1] = r.x;
    EXPECT_EQ(r.x, x[0]);
  }
}

// Point-to-plane with the queries of each 4 cm cube sharing their local planes: fewer fits (half
// here, with this room's rays 1.2 degrees apart in elevation, about two queries to a cube; a
// third on rig B's drive), the same estimate as every query fitting its own (within a fifth of
// its sigma), and the same bits on any number of threads.
TEST(OverlapAlignment, QueriesInOneCellShareTheirLocalPlanes) {
  const std::vector<Eigen::Vector3d> origins = {{-0.4, 0.1, 0.8}, {0.5, -0.2, 1.1}};
  std::mt19937 rng(11);
  std::vector<OverlapRay> rays;
  scan(origins[0], 720, 120, false, 0.01, &rng, &rays);
  scan(origins[1], 360, 60, true, 0.01, &rng, &rays);
  const auto align = [&](double cell_m, int threads) {
    ShiftModel model(rays, origins);
    OverlapOptions oo;
    oo.base.max_incidence_rad = 1.2;
    oo.plane_cell_m = cell_m;
    oo.threads = threads;
    const OverlapResult r = alignOverlap(rays, model, Eigen::VectorXd::Zero(3), oo);
    EXPECT_TRUE(r.ok) << r.reason;
    return r;
  };
  const OverlapResult own = align(0.0, 2), shared = align(0.04, 2);
  EXPECT_LT(shared.local_planes, 0.6 * double(own.local_planes));
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(shared.x(k), own.x(k), 0.2 * std::sqrt(own.covariance(k, k))) << k;
  }
  for (int t : {1, 3}) EXPECT_EQ(align(0.04, t).x, shared.x) << t << " threads";
}

// Widening a covariance to another's variances: each smaller variance raised to the other's, the
// larger kept, the correlations unchanged (rig B's calib rig widens the patches' covariance to
// point-to-plane's this way).
TEST(OverlapAlignment, WidenedToRaisesOnlyTheSmallerVariancesAndKeepsTheCorrelations) {
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(4, 4);  // the last parameter held
  cov.topLeftCorner<3, 3>() << 4.0, 1.2, -0.6,        //
      1.2, 1.0, 0.3,                                  //
      -0.6, 0.3, 0.25;
  const Eigen::VectorXd other = Eigen::Vector4d(1.0, 9.0, 0.0, 2.0);
  const Eigen::MatrixXd w = widenedTo(cov, other);
  EXPECT_DOUBLE_EQ(w(0, 0), 4.0);  // already wider
  EXPECT_DOUBLE_EQ(w(1, 1), 9.0);
  EXPECT_DOUBLE_EQ(w(2, 2), 0.25);
  EXPECT_EQ(w.row(3).norm(), 0.0);  // held: stays held
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(w(i, j) / std::sqrt(w(i, i) * w(j, j)),
                  cov(i, j) / std::sqrt(cov(i, i) * cov(j, j)), 1e-12)
          << i << ", " << j;
    }
  }
}

}  // namespace
}  // namespace sweepmap
