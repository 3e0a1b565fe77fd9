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
// A wall counts when each pass has this many points in its band: the median of 100 points
// of noise sigma is known to 0.125 sigma (1.25 sigma / sqrt(100)), 6 mm at 4.5 m with 1 %.
constexpr int kMinWallPoints = 100;
constexpr double kBandSigmas = 3.0;  // the band: +-3 sigma of each point's range noise
// The first band's widening: a wall fitted to the whole drive can sit centimetres off one
// pass's copy (the ghost itself).
constexpr double kSeedBandM = 0.06;
constexpr double kSettledM = 1e-4;
constexpr int kMaxRounds = 50;

// The lidar's origin in the world at each scan's middle ray (nullopt: no pose then).
std::vector<std::optional<Eigen::Vector3d>> scanOrigins(const MobileLog& log,
                                                        const PoseTrack& track,
                                                        const LidarMounting& mounting) {
  const Eigen::Vector3d t_BL = mounting.T_BL().translation();
  std::vector<std::optional<Eigen::Vector3d>> origin(log.scans.size());
  for (size_t j = 0; j < log.scans.size(); ++j) {
    const Scan2D& s = log.scans[j];
    const auto pose = track.at(s.rayUtime(s.ranges_m.size() / 2));
    if (!pose) continue;
    const double c = std::cos(pose->theta_rad), si = std::sin(pose->theta_rad);
    origin[j] = Eigen::Vector3d(pose->x_m + c * t_BL.x() - si * t_BL.y(),
                                pose->y_m + si * t_BL.x() + c * t_BL.y(), t_BL.z());
  }
  return origin;
}

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

// One pass's points and, for each, the lidar's origin when it was measured.
struct PassPoints {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3d> origins;
};

PassPoints passPoints(const std::vector<Eigen::Vector3f>& cloud,
                      const std::vector<int>& scan_of_point, const std::vector<int>& scans,
                      const std::vector<std::optional<Eigen::Vector3d>>& origin) {
  std::vector<char> wanted(origin.size(), 0);
  for (int j : scans) wanted[size_t(j)] = origin[size_t(j)] ? 1 : 0;
  PassPoints p;
  for (size_t k = 0; k < cloud.size(); ++k) {
    const size_t j = size_t(scan_of_point[k]);
    if (!wanted[j]) continue;
    p.points.push_back(cloud[k]);
    p.origins.push_back(*origin[j]);
  }
  return p;
}

double median(std::vector<double> v) {
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + long(mid), v.end());
  return v[mid];
}

// One pass's copy of the wall (n, offset): the median offset along n of the pass's points
// within +-3 sigma of the copy, sigma being the range noise seen along the normal
// (range_sigma_fraction x range x cos(incidence) = range_sigma_fraction x the distance of the
// point's lidar origin from the wall). The band starts around the seed plane, widened by
// kSeedBandM, then follows the copy's median until it moves less than 0.1 mm (a truncated
// band pulls the median toward its centre, so one round is not enough on a far wall). Rays lying in
// the plane (a vertical lidar's own scan plane, which RANSAC can take for a wall) have no band.
// Nullopt with fewer than kMinWallPoints points in the band.
std::optional<double> passCopy(const PassPoints& pass, const Eigen::Vector3d& n, double offset,
                               double range_sigma_fraction, int* points) {
  double centre = 0.0;
  for (int round = 0; round < kMaxRounds; ++round) {
    const double widen = round == 0 ? kSeedBandM : 0.0;
    std::vector<double> d;
    for (size_t k = 0; k < pass.points.size(); ++k) {
      const double dist = n.dot(pass.points[k].cast<double>()) + offset;
      const double sigma = range_sigma_fraction * std::abs(n.dot(pass.origins[k]) + offset);
      if (std::abs(dist - centre) <= kBandSigmas * sigma + widen) d.push_back(dist);
    }
    *points = int(d.size());
    if (*points < kMinWallPoints) return std::nullopt;
    const double next = median(std::move(d));
    const bool settled = round > 0 && std::abs(next - centre) < kSettledM;
    centre = next;
    if (settled) break;
  }
  return centre;
}

// The wall near the vertical plane `seed` (its normal made horizontal) in both passes: each
// pass's copy, their distance, and the plane midway. Nullopt when a pass has too few points
// in its band (it does not see that wall there).
std::optional<LoopClosure::Plane> measureWall(const WallPlaneFit& seed, const PassPoints& early,
                                              const PassPoints& late, double range_sigma_fraction) {
  LoopClosure::Plane w;
  w.normal = Eigen::Vector3d(seed.normal.x(), seed.normal.y(), 0.0).normalized();
  const auto e = passCopy(early, w.normal, seed.offset, range_sigma_fraction, &w.early_points);
  const auto l = passCopy(late, w.normal, seed.offset, range_sigma_fraction, &w.late_points);
  if (!e || !l) return std::nullopt;
  w.distance_m = std::abs(*l - *e);
  w.offset_m = seed.offset - 0.5 * (*e + *l);
  // Where the wall is, for the report: the early pass's mean lidar origin's foot on it.
  Eigen::Vector3d o = Eigen::Vector3d::Zero();
  for (const auto& x : early.origins) o += x;
  o /= double(early.origins.size());
  w.range_m = std::abs(w.normal.dot(o) + w.offset_m);
  w.foot_m = o - (w.normal.dot(o) + w.offset_m) * w.normal;
  return w;
}

// Each of the room's walls that both passes see, measured by measureWall.
void measurePassWalls(const std::vector<WallPlaneFit>& walls, const PassPoints& early,
                      const PassPoints& late, double range_sigma_fraction, LoopClosure* lc) {
  for (const WallPlaneFit& wall : walls) {
    const auto w = measureWall(wall, early, late, range_sigma_fraction);
    if (!w) continue;
    lc->planes.push_back(*w);
    lc->ghost_m = std::max(lc->ghost_m.value_or(0.0), w->distance_m);
  }
}

}  // namespace

RoomDims refinedRoomDims(const MobileLog& log, const PoseTrack& track,
                         const std::vector<Eigen::Vector3f>& cloud,
                         const std::vector<int>& scan_of_point, const LidarMounting& mounting,
                         const RoomPlanes& planes, double range_sigma_fraction) {
  const auto origin = scanOrigins(log, track, mounting);
  std::vector<Eigen::Vector3f> points, origins;
  RangeNoise noise;
  noise.fraction = range_sigma_fraction;
  for (const Scan2D& s : log.scans) noise.range_max_m = std::max(noise.range_max_m, s.range_max_m);
  for (size_t k = 0; k < cloud.size(); ++k) {
    const auto& o = origin[size_t(scan_of_point[k])];
    if (!o) continue;
    points.push_back(cloud[k]);
    origins.push_back(o->cast<float>());
  }
  return sweepmap::refinedRoomDims(planes, points, origins, noise);
}

LoopClosure loopClosure(const MobileLog& log, const PoseTrack& track,
                        const std::vector<Eigen::Vector3f>& cloud,
                        const std::vector<int>& scan_of_point, const LidarMounting& mounting,
                        const std::vector<WallPlaneFit>& walls, double range_sigma_fraction) {
  LoopClosure lc;
  findRevisits(log, track, &lc);
  if (lc.early.size() < 5 || lc.late.size() < 5) {
    lc.reason =
        "the drive does not come back to a place it passed " + fixed(kMinGapS, 0) + " s earlier";
    return lc;
  }
  const auto origin = scanOrigins(log, track, mounting);
  const PassPoints early = passPoints(cloud, scan_of_point, lc.early, origin);
  const PassPoints late = passPoints(cloud, scan_of_point, lc.late, origin);
  measurePassWalls(walls, early, late, range_sigma_fraction, &lc);
  if (!lc.ghost_m)
    lc.reason = walls.empty() ? "no room walls found" : "no room wall seen by both passes";
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

}  // namespace

HalfScanGhost halfScanGhost(const MobileLog& log, const PoseTrack& track,
                            const LidarMounting& mounting, double range_sigma_fraction) {
  HalfScanGhost g;
  const Eigen::Isometry3d T_BL = mounting.T_BL();
  const auto origin = scanOrigins(log, track, mounting);
  PassPoints halves[2];  // left, right: each point with its scan's lidar origin
  for (size_t j = 0; j < log.scans.size(); ++j) {
    if (!origin[j]) continue;
    for (bool left : {true, false}) {
      const auto pts = scanToWorld(scanHalf(log.scans[j], left), track, T_BL);
      PassPoints& h = halves[left ? 0 : 1];
      h.points.insert(h.points.end(), pts.begin(), pts.end());
      h.origins.insert(h.origins.end(), pts.size(), *origin[j]);
    }
  }
  g.left = halves[0].points;
  g.right = halves[1].points;
  // The walls of both halves together (the circle sees the far walls only at grazing, noisy
  // ranges: any large vertical plane will do, not necessarily four facing walls; a band of 6 cm
  // catches both copies of a wall doubled by a few centimetres), then each half's copy as the
  // loop's ghost measures a pass's: the median within +-3 sigma of each point's range noise.
  // Not a plane refitted in each half in a fixed band: the lab's far wall, 9-11 m from the
  // circle, has +-100 mm of noise, and a fixed band kept part of its seed's error.
  std::vector<Eigen::Vector3f> both = g.left;
  both.insert(both.end(), g.right.begin(), g.right.end());
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
    const auto m = measureWall(w, halves[0], halves[1], range_sigma_fraction);
    if (!m) continue;
    g.walls.wall_distance_m.push_back(m->distance_m);
    g.walls.max_m = std::max(g.walls.max_m.value_or(0.0), m->distance_m);
  }
  if (!g.walls.max_m) g.walls.reason = "no wall seen by both halves";
  return g;
}

}  // namespace sweepmap::eval
