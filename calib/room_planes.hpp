// A room's planes and dimensions in a world-frame cloud (Miao 2022 section 5): the four walls
// (calib/walls.hpp's RANSAC extraction, one thread), the floor and the ceiling, and the
// wall-to-wall distances. Used by rig B's evaluation (tools/eval) and by calib rig, which
// compares them with the scene's.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "calib/walls.hpp"

namespace sweepmap {

// The centroid of the points `idx` of `cloud` (zero without any).
Eigen::Vector3d inlierCentroid(const std::vector<Eigen::Vector3f>& cloud,
                               const std::vector<int>& idx);

double signedDistance(const WallPlaneFit& p, const Eigen::Vector3d& x);

// Distance of two near-parallel planes: the mean of each one's distance from the other's
// inlier centroid (symmetric; exact for parallel planes).
double planeDistance(const WallPlaneFit& a, const std::vector<Eigen::Vector3f>& cloud_a,
                     const WallPlaneFit& b, const std::vector<Eigen::Vector3f>& cloud_b);

// The room's planes found by RANSAC in a world-frame cloud.
struct RoomPlanes {
  std::vector<WallPlaneFit> walls;  // extractWalls' order: normals ~ +Y, +X, -Y, -X
  std::optional<WallPlaneFit> floor, ceiling;
  std::string reason;  // what is missing
};
RoomPlanes findRoomPlanes(const std::vector<Eigen::Vector3f>& cloud,
                          const WallExtractionOptions& walls = WallExtractionOptions{});

struct RoomDims {
  std::optional<double> L1, L2, L3;  // length, width (the longer and shorter wall spacing), height
  // Their sigmas from the two planes' offset sigmas (RefinedPlane::offset_sigma); 0: none
  // (roomDims' RANSAC planes).
  double L1_sigma = 0.0, L2_sigma = 0.0, L3_sigma = 0.0;
};
RoomDims roomDims(const RoomPlanes& planes, const std::vector<Eigen::Vector3f>& cloud);

// A plane of a lidar's cloud refined against the lidar's range noise (calib rig's room and
// floor). A point's noise along the plane's normal is the range's, fraction f of the range,
// times the cosine of its incidence: f times its origin's distance from the plane, whatever
// the ray. So a wall seen from 9 m scatters +-90 mm along its normal, the floor under a lidar
// 0.3 m up +-3 mm: one fixed window (RANSAC's 30 mm) keeps the near wall's bumps and cuts a
// far wall's noise on one side wherever its RANSAC plane sits. Here each point's window is
// window_sigmas of its own sigma and its weight the inverse variance, iterated to a fixed
// point (symmetric about the plane: unbiased). And a lidar loses the returns measured beyond
// its range_max_m: near that range only the short ones are left, which pulls a far wall
// towards the lidar. A ray whose range to the plane (predicted by the plane, not measured) is
// within window_sigmas of its noise below range_max_m is left out: which rays remain no
// longer depends on their noise.
struct RangeNoise {
  double fraction = 0.01;
  double range_max_m = 0.0;  // 0: no limit
  double floor_m = 0.001;    // added in quadrature to each sigma (the model's own error)
  double window_sigmas = 3.0;
  int iterations = 12;
};
// Clutter proud of a plane (a whiteboard on a wall, a poster, a shelf's back) lies within a
// far wall's window: a 20 mm whiteboard on the lab's far wall, seen from 5.5-9.5 m (points
// +-55-95 mm along the normal), pulled the wall 2-2.6 mm in. No point tells it apart, but the
// region does: its rays' weighted mean stands proud of the rest by many sigmas of that mean.
// After the fixed point, the axis-aligned rectangle of in-plane cells (each ray at the point
// where it meets the plane, so which cell does not depend on its noise) whose mean stands
// proud of the rest's, towards the lidar, by at least min_m and `sigmas` of the difference's
// sigma is left out, grown by one cell, and the plane refined again; up to max_regions times.
// Only towards the lidar: nothing stands behind a wall, and a recess (a door, a window) lies
// beyond the window of the wall's near views (not handled: a recess in a wall seen only from
// afar, whose window holds it). At most max_share of the plane's weight is left out in all: a
// plane smeared by a wrong calibration stands proud here and there, and taking out one side
// would push it back. The threshold has a thin margin on a wall seen only from afar (see
// `sigmas`).
struct ClutterSearch {
  // Larger than the track's error between two views of a wall (rig B: 1.5-3.9 mm at most),
  // which no region of clutter should be mistaken for.
  double min_m = 0.008;
  // Above the rectangle that stands out most on a bare wall (2.5-4.1 sigmas on synthetic walls
  // of 2,000-20,000 points); the lab's whiteboard on the far wall of calib plan's drive stood
  // out by 4.5 (seed 2).
  double sigmas = 4.5;
  // A best region between this and `sigmas` may be clutter or chance: it is not taken out, but
  // the offset's sigma grows by how far taking it out would move the plane (on seed 2 of the
  // plan's drive the whiteboard stood out by less than 4.5 once the calibration moved by a
  // fraction of its sigma, and the room came out 6.5 mm short at 3.7 of its sigmas).
  double ambiguous_sigmas = 3.5;
  double cell_m = 0.25;
  int max_regions = 3;
  double max_share = 0.5;  // of the plane's weight, all regions together (grown)
};
struct RefinedPlane {
  bool ok = false;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;                                 // normal.dot(p) + offset = 0
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // of the inliers, weighted
  std::vector<int> inliers;
  std::vector<double> weights;  // of each inlier: 1 / sigma^2
  int clutter_regions = 0;      // regions left out as clutter proud of the plane
  // How far leaving out a region that stood out by ambiguous_sigmas to sigmas would have moved
  // the plane at its centroid (0: none did, or the search ended at max_regions or max_share
  // before looking); offset_sigma holds it.
  double ambiguity_m = 0.0;
  // The sigma of the plane's offset at its centroid: the weighted mean's, cluster-robust over
  // in-plane cells of kOffsetClusterM (the points of a cell err together: one stretch of the
  // track saw them), never below what the points' own noise gives.
  double offset_sigma = 0.0;
  int offset_cells = 0;  // the cells it is cluster-robust over
};
constexpr double kOffsetClusterM = 0.5;
// `origins[i]`: where the lidar was when it measured cloud[i]. Starts from `start` (a RANSAC
// plane); not ok when fewer than 10 points remain.
// `nearer`: the room's other planes (normal, offset). Where two surfaces meet (a wall and the
// ceiling, two walls), the other's points within this plane's window all lie on the room's
// side of it and pull it inwards (the ceiling's top 60-80 mm strip of wall: the room came out
// 1.3-2.2 mm narrow and 0.4-0.5 mm low on every seed). A ray whose predicted range to one of
// them is shorter than to this plane, or within window_sigmas of its noise beyond, meets that
// one first and is left out; chosen by the predicted ranges, which rays remain does not depend
// on their noise.
struct PlaneEquation {
  Eigen::Vector3d normal;
  double offset;
};
// `search`: the clutter search after the fixed point (none: the fixed point alone); a region
// that stands out by ambiguous_sigmas but not by sigmas stays, and widens offset_sigma.
RefinedPlane refinePlane(const std::vector<Eigen::Vector3f>& cloud,
                         const std::vector<Eigen::Vector3f>& origins, const WallPlaneFit& start,
                         const RangeNoise& noise, const std::vector<PlaneEquation>& nearer = {},
                         const std::optional<ClutterSearch>& search = std::nullopt);
// The distance of two near-parallel refined planes: the mean of each one's distance from the
// other's weighted centroid.
double refinedDistance(const RefinedPlane& a, const RefinedPlane& b);
// Its sigma: the two offsets' sigmas in quadrature (each plane's tilt, at the other's centroid,
// left out: the planes face each other across the room's middle).
double refinedDistanceSigma(const RefinedPlane& a, const RefinedPlane& b);
// The room's length, width and height from refined planes (RoomPlanes' walls, floor and
// ceiling refined in its cloud: each alone without the clutter search, then each again with
// the others as `nearer` and with `clutter`), with their sigmas.
RoomDims refinedRoomDims(const RoomPlanes& planes, const std::vector<Eigen::Vector3f>& cloud,
                         const std::vector<Eigen::Vector3f>& origins, const RangeNoise& noise,
                         const ClutterSearch& clutter = {});

}  // namespace sweepmap
