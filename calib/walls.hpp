// The four walls of a room in a 3D sweep (Yuan 2021 section 4.2, Fig. 7): the planes whose
// unit normals n_1..n_4 feed the attitude error E_atti (Eq. 11) and the plate-angle
// calibration (Eq. 16-20). Also used by evaluation for plane deviations (Appendix B).
// PCL stays in walls.cpp: this header is plain Eigen.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace sweepmap {

struct WallPlaneFit {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit, |normal.z| small, pointing toward the
                                                     // cloud's origin (the sensor)
  double offset = 0;  // normal.dot(p) + offset = 0, frame of the input cloud; > 0: origin in front
  int inliers = 0;
  double rms_m = 0;                 // RMS point-to-plane distance of the inliers
  std::vector<int> inlier_indices;  // into the cloud the fit was made on (see extractWalls)
};

struct WallExtractionOptions {
  double voxel_m = 0.05;  // downsample first (pcl::VoxelGrid): speed
  double distance_threshold_m = 0.03;
  int max_planes = 8;                  // RANSAC planes tried, largest first
  double max_normal_z = 0.1;           // vertical walls only: |normal.z| <= this
  int min_inliers = 300;               // after downsampling
  double parallel_tolerance_deg = 10;  // two near-parallel pairs, roughly perpendicular
  int ransac_max_iterations = 1000;
  // Before RANSAC, drop the points of horizontal surfaces (floor, ceiling): z-slices of the
  // downsampled cloud, `voxel_m` thick, holding more than this many times the median slice
  // count. Walls fill every slice evenly; a floor or ceiling fills one or two. 0: off.
  double horizontal_peak_factor = 4.0;
};

struct WallExtraction {
  // Empty, or exactly four walls ordered by the direction of their normals (which point
  // toward the sensor, i.e. into the room):
  //   walls[0]: normal nearest +Y   (the wall on the sensor's -Y side)
  //   walls[1]: normal nearest +X   (the wall behind, -X side)
  //   walls[2]: normal nearest -Y   (the wall on the +Y side)
  //   walls[3]: normal nearest -X   (the wall in front, +X side)
  // so walls[0], walls[2] are n_1, n_3 of Eq. 11 (perpendicular to i) and walls[1],
  // walls[3] are n_2, n_4 (perpendicular to j). inlier_indices index the input cloud.
  std::vector<WallPlaneFit> walls;
  std::string reason;        // why `walls` is empty
  int candidate_planes = 0;  // vertical planes of at least min_inliers found by RANSAC
};

// Extracts the four walls of a room from a cloud in frame O (metres, Z up): voxel
// downsampling, removal of horizontal slabs (floor, ceiling), then up to `max_planes`
// RANSAC planes constrained vertical (pcl::SACSegmentation, SACMODEL_PARALLEL_PLANE with
// axis Z; PCL's fixed seed makes it deterministic), largest first, each removed before the
// next. Among the vertical planes of at least `min_inliers`, picks the two pairs of
// opposite, near-antiparallel planes (normals facing each other within the tolerance) that
// are roughly perpendicular to each other, maximising the total inlier count: clutter (a
// door recess, a cabinet front) gives smaller planes and loses. Each chosen plane is refit
// by least squares on the full-resolution points within `distance_threshold_m`.
WallExtraction extractWalls(const std::vector<Eigen::Vector3f>& cloud_O,
                            const WallExtractionOptions& options = {});

// Refits the given planes on `cloud` (typically the full-resolution cloud): the points
// within `distance_m` of each plane, a least-squares plane through them, then the points
// within `distance_m` of that plane (inlier_indices, rms_m). The normal keeps the
// orientation of the input. A plane with fewer than 3 points is returned with inliers = 0.
std::vector<WallPlaneFit> refitWalls(const std::vector<Eigen::Vector3f>& cloud,
                                     const std::vector<WallPlaneFit>& walls, double distance_m);

// The least-squares plane through cloud[idx] (the smallest eigenvector of their covariance):
// normal . p + offset = 0. False for fewer than 3 points.
bool fitPlaneLeastSquares(const std::vector<Eigen::Vector3f>& cloud, const std::vector<int>& idx,
                          Eigen::Vector3d* normal, double* offset);

// Planes of any orientation, or horizontal ones (floor, ceiling, table tops), for rig B's
// evaluation: voxel downsampling, then up to `max_planes` RANSAC planes (PCL's fixed seed:
// deterministic), largest first, each removed before the next; each refit by least squares
// on the full-resolution points within `distance_threshold_m` (indices into `cloud`).
// Normals point toward the cloud's origin (offset >= 0).
struct PlaneExtractionOptions {
  enum class Orientation { kAny, kHorizontal, kVertical };
  Orientation orientation = Orientation::kAny;
  double max_tilt_deg = 10.0;  // kHorizontal / kVertical: allowed deviation
  double voxel_m = 0.05;
  double distance_threshold_m = 0.03;
  int max_planes = 6;
  int min_inliers = 300;  // after downsampling
  int ransac_max_iterations = 1000;
};
std::vector<WallPlaneFit> extractPlanes(const std::vector<Eigen::Vector3f>& cloud,
                                        const PlaneExtractionOptions& options);

}  // namespace sweepmap
