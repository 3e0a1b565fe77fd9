#include "tools/eval/mobile_metrics.hpp"

#include <algorithm>
#include <cmath>

#include "core/angles.hpp"
#include "tools/eval/common.hpp"

namespace sweepmap::eval {

TrajectoryErrors trajectoryErrors(const PoseTrack& estimate, const PoseTrack& truth) {
  TrajectoryErrors e;
  if (estimate.size() == 0 || truth.size() == 0) return e;
  const int64_t t0 = truth.poses().begin()->first;
  double ss = 0, mx = 0, hs = 0, hm = 0;
  for (const auto& [utime, p] : estimate.poses()) {
    const auto t = truth.at(utime);
    if (!t) continue;
    const double d = std::hypot(p.x_m - t->x_m, p.y_m - t->y_m);
    const double h = wrapAngle(p.theta_rad - t->theta_rad);
    e.t_s.push_back(1e-6 * static_cast<double>(utime - t0));
    e.error_m.push_back(d);
    e.heading_error_rad.push_back(h);
    ss += d * d;
    mx = std::max(mx, d);
    hs += h * h;
    hm = std::max(hm, std::abs(h));
  }
  if (e.error_m.empty()) return e;
  e.rmse_m = std::sqrt(ss / static_cast<double>(e.error_m.size()));
  e.heading_rmse_rad = std::sqrt(hs / static_cast<double>(e.error_m.size()));
  e.heading_max_rad = hm;
  e.final_m = e.error_m.back();
  e.max_m = mx;
  return e;
}

namespace {

// The mean signed distance from `plane` of the inliers of `fit` (indices into `points`).
double meanOffset(const WallPlaneFit& plane, const std::vector<Eigen::Vector3f>& points,
                  const WallPlaneFit& fit) {
  double sum = 0.0;
  for (int i : fit.inlier_indices) sum += signedDistance(plane, points[size_t(i)].cast<double>());
  return sum / double(fit.inlier_indices.size());
}

// Deviations (mm) of the points near each plane, for the histograms of Fig. 9.
DeviationStats deviations(const std::vector<Eigen::Vector3f>& cloud,
                          const std::vector<WallPlaneFit>& planes, double edge_trim_m) {
  std::vector<PlaneForDeviation> pd;
  for (const auto& p : planes) pd.push_back({p.normal, p.offset});
  DeviationStats stats(1.0, 50.0);
  for (const auto& v : wallDeviationsMm(cloud, pd, 0.05, edge_trim_m)) {
    for (double d : v) stats.add(d, 10.0);
  }
  return stats;
}

}  // namespace

RoomMeasures measureRoom(const std::vector<Eigen::Vector3f>& cloud) {
  RoomMeasures m;
  m.planes = findRoomPlanes(cloud);
  m.dims = roomDims(m.planes, cloud);
  const std::vector<WallPlaneFit> ceiling =
      m.planes.ceiling ? std::vector<WallPlaneFit>{*m.planes.ceiling} : std::vector<WallPlaneFit>{};
  m.ceiling = deviations(cloud, ceiling, 0.0);
  m.walls = deviations(cloud, m.planes.walls, 0.2);
  if (m.planes.ceiling) {
    m.ceiling_up = m.planes.ceiling->normal;
    if (m.ceiling_up->z() < 0) *m.ceiling_up = -*m.ceiling_up;
  }
  return m;
}

// --- the loop's ghost ------------------------------------------------------------------------

std::vector<Eigen::Vector3f> pointsOfScans(const std::vector<Eigen::Vector3f>& cloud,
                                           const std::vector<int>& scan_of_point,
                                           const std::vector<int>& scans, size_t scan_count) {
  std::vector<char> wanted(scan_count, 0);
  for (int j : scans) wanted[static_cast<size_t>(j)] = 1;
  std::vector<Eigen::Vector3f> out;
  for (size_t k = 0; k < cloud.size(); ++k) {
    if (wanted[static_cast<size_t>(scan_of_point[k])]) out.push_back(cloud[k]);
  }
  return out;
}

namespace {

constexpr double kMinGapS = 30.0, kRadiusM = 0.3, kHeadingRad = 0.35;

// The scans of the early pass (not also late) and of the late pass, into lc.early / lc.late.
void findRevisits(const MobileLog& log, const PoseTrack& track, LoopClosure* lc) {
  std::vector<std::optional<Pose2>> pose(log.scans.size());
  for (size_t j = 0; j < log.scans.size(); ++j) {
    const Scan2D& s = log.scans[j];
    pose[j] = track.at(s.rayUtime(s.ranges_m.size() / 2));
  }
  std::vector<char> is_early(log.scans.size(), 0), is_late(log.scans.size(), 0);
  for (size_t j = 0; j < log.scans.size(); ++j) {
    if (!pose[j]) continue;
    for (size_t i = 0; i < j; ++i) {
      if (!pose[i] ||
          1e-6 * static_cast<double>(log.scans[j].utime - log.scans[i].utime) < kMinGapS)
        continue;
      if (std::hypot(pose[j]->x_m - pose[i]->x_m, pose[j]->y_m - pose[i]->y_m) > kRadiusM) continue;
      if (std::abs(wrapAngle(pose[j]->theta_rad - pose[i]->theta_rad)) > kHeadingRad) continue;
      is_early[i] = 1;
      is_late[j] = 1;
    }
  }
  for (size_t j = 0; j < log.scans.size(); ++j) {
    if (is_early[j] && !is_late[j]) lc->early.push_back(static_cast<int>(j));
    if (is_late[j]) lc->late.push_back(static_cast<int>(j));
  }
}

// Each vertical plane of the early pass, refitted in the late pass's points, and their distance.
void matchPassPlanes(const std::vector<Eigen::Vector3f>& early_pts,
                     const std::vector<Eigen::Vector3f>& late_pts, LoopClosure* lc) {
  PlaneExtractionOptions po;
  po.orientation = PlaneExtractionOptions::Orientation::kVertical;
  po.voxel_m = 0.03;
  po.max_planes = 4;
  po.min_inliers = 100;
  po.distance_threshold_m = 0.03;
  for (const WallPlaneFit& e : extractPlanes(early_pts, po)) {
    // A far, noisy wall (1 % of 5 m) can come out of RANSAC as two parallel planes a few
    // centimetres apart, the second made of the first one's outliers: one surface, one plane.
    const Eigen::Vector3d c = inlierCentroid(early_pts, e.inlier_indices);
    const bool seen =
        std::any_of(lc->planes.begin(), lc->planes.end(), [&](const LoopClosure::Plane& q) {
          return std::abs(q.early.normal.dot(e.normal)) > std::cos(3.0 * M_PI / 180.0) &&
                 std::abs(signedDistance(q.early, c)) < 0.1;
        });
    if (seen) continue;
    const auto refit = refitWalls(late_pts, {e}, 0.1);
    if (refit.empty() || refit[0].inliers < 100) continue;
    // The late pass's plane through its points near the early plane, then its own inliers.
    const auto late = refitWalls(late_pts, refit, po.distance_threshold_m);
    if (late.empty() || late[0].inliers < 100) continue;
    // The two passes' copies apart along the early wall's horizontal normal (a wall is
    // vertical): each pass's inliers averaged. A RANSAC plane through a far wall's sparse points
    // can tilt by a degree; the distance of one pass's plane from the other's centroid then
    // grows with the height between the centroids, not with the ghost (29 mm on the lab's wall
    // 5 m off, where the passes' own offsets agree to a few millimetres).
    WallPlaneFit vertical = e;
    vertical.normal.z() = 0.0;
    vertical.normal.normalize();
    const double distance_m =
        std::abs(meanOffset(vertical, late_pts, late[0]) - meanOffset(vertical, early_pts, e));
    LoopClosure::Plane p{e, late[0], distance_m};
    lc->planes.push_back(p);
    lc->ghost_m = std::max(lc->ghost_m.value_or(0.0), p.distance_m);
  }
}

}  // namespace

LoopClosure loopClosure(const MobileLog& log, const PoseTrack& track,
                        const std::vector<Eigen::Vector3f>& cloud,
                        const std::vector<int>& scan_of_point) {
  LoopClosure lc;
  findRevisits(log, track, &lc);
  if (lc.early.size() < 5 || lc.late.size() < 5) {
    lc.reason =
        "the drive does not come back to a place it passed " + fixed(kMinGapS, 0) + " s earlier";
    return lc;
  }
  std::vector<Eigen::Vector3f> early_pts =
      pointsOfScans(cloud, scan_of_point, lc.early, log.scans.size());
  const std::vector<Eigen::Vector3f> late_pts =
      pointsOfScans(cloud, scan_of_point, lc.late, log.scans.size());
  matchPassPlanes(early_pts, late_pts, &lc);
  if (!lc.ghost_m) lc.reason = "no wall seen by both passes";
  lc.early_points = std::move(early_pts);
  return lc;
}

// --- the circle's double walls -----------------------------------------------------------------

namespace {

// The scan's rays on one side of the lidar's Z_L-axis only (left: angles in (0, pi), toward
// +Y_L, the body's left with the nominal vertical mounting); the others become "no return".
// So do returns beyond 90 % of the maximum range: near it only the readings whose noise made
// them short survive, so a wall there is biased toward the sensor, more for the pass that sees
// it from farther (18 mm on the lab's far wall, 9-11 m from the circle).
Scan2D scanHalf(const Scan2D& scan, bool left) {
  Scan2D half = scan;
  const float far = float(0.9 * scan.range_max_m);
  for (size_t i = 0; i < half.ranges_m.size(); ++i) {
    const bool is_left = std::sin(half.rayAngle(i)) > 0.0;
    if (is_left != left || half.ranges_m[i] > far) half.ranges_m[i] = 0.0f;
  }
  return half;
}

// The wall refitted in one half's points: a band wide enough to hold both copies of a
// doubled wall, then the half's own inliers; none with fewer than 100 points.
std::optional<WallPlaneFit> refitInHalf(const std::vector<Eigen::Vector3f>& half,
                                        const WallPlaneFit& w) {
  const auto wide = refitWalls(half, {w}, 0.15);
  if (wide.empty() || wide[0].inliers < 100) return std::nullopt;
  const auto tight = refitWalls(half, wide, 0.03);
  if (tight.empty() || tight[0].inliers < 100) return std::nullopt;
  return tight[0];
}

}  // namespace

HalfScanGhost halfScanGhost(const MobileLog& log, const PoseTrack& track,
                            const LidarMounting& mounting) {
  HalfScanGhost g;
  const Eigen::Isometry3d T_BL = mounting.T_BL();
  for (const Scan2D& s : log.scans) {
    for (bool left : {true, false}) {
      const auto pts = scanToWorld(scanHalf(s, left), track, T_BL);
      auto& dst = left ? g.left : g.right;
      dst.insert(dst.end(), pts.begin(), pts.end());
    }
  }
  // The walls of both halves together, then each wall refitted in each half on its own.
  std::vector<Eigen::Vector3f> both = g.left;
  both.insert(both.end(), g.right.begin(), g.right.end());
  // Vertical planes (the circle sees the far walls only at grazing, noisy ranges: any large
  // vertical plane will do, not necessarily four facing walls). A band of 6 cm catches both
  // copies of a wall doubled by a few centimetres.
  PlaneExtractionOptions po;
  po.orientation = PlaneExtractionOptions::Orientation::kVertical;
  po.distance_threshold_m = 0.06;
  po.max_planes = 4;
  const std::vector<WallPlaneFit> walls = extractPlanes(both, po);
  if (walls.empty()) {
    g.walls.reason = "no vertical plane found";
    return g;
  }
  for (const WallPlaneFit& w : walls) {
    const auto l = refitInHalf(g.left, w), r = refitInHalf(g.right, w);
    if (!l || !r) continue;
    // The two copies' offsets along the common normal (both halves' fit): each half's
    // inliers averaged, so a far, sparse wall's noisy tilt does not reach the other copy
    // over a lever of metres (as the distance of one half's plane from the other's
    // centroid did: 16 mm on the lab's far wall, 10 m from the circle, after calibration).
    const double d = std::abs(meanOffset(w, g.left, *l) - meanOffset(w, g.right, *r));
    g.walls.wall_distance_m.push_back(d);
    g.walls.max_m = std::max(g.walls.max_m.value_or(0.0), d);
  }
  if (!g.walls.max_m) g.walls.reason = "no wall seen by both halves";
  return g;
}

}  // namespace sweepmap::eval
