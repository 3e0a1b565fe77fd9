// Calibration of a rotating 2D lidar's offset from its rotation axis (rig A, t_L^O' of Yuan
// 2021 Eq. 5-6, nominal (13.9, 0, 0) mm) by the plane constraint of Zhao 2021: the points
// of the room's walls, floor and ceiling must each lie on a plane.
//
// Model (calib/rotating_geometry.hpp): a ray of range r at angle theta in the scan, taken at
// shaft angle phi, is the point p = Rz(phi) (t + r (0, sin theta, cos theta)), t = (x, y, z):
// x across the scan plane (the paper's offset), y within it perpendicular to the axis, z
// along the axis. For a plane n . p = d the residual's derivative by t is Rz(phi)^T n:
//  - z: n_z, the same for every point of a plane, so each plane's distance absorbs it: a
//    shift along the axis moves the whole cloud and is never observable;
//  - x, y: (n_x cos phi + n_y sin phi, -n_x sin phi + n_y cos phi), zero for planes
//    perpendicular to the axis (floor, ceiling: they constrain nothing here) and varying
//    with phi for planes parallel to it (vertical walls): a wrong x or y bends the walls,
//    which the planes cannot absorb. Walls seen over a wide range of phi determine them.
// The rig's model has t = (x, 0, 0): x is estimated (y optionally, reported only), z held.
//
// The method: each sweep's planes are found by PCL RANSAC on the cloud assembled with the
// nominal offset (calib/walls.hpp extractPlanes), every point assigned to the plane it is
// near (points near two planes, at edges, dropped), then one least-squares problem in Ceres
// over the offset and every plane (unit normal on the sphere + distance) with Cauchy-weighted
// point-to-plane residuals (iteratively reweighted: edges and clutter lose their pull), the
// offset's standard deviation (calib/parameter_information.hpp) and a check of which components the
// planes determine (the Jacobian with the planes eliminated, plane by plane).
// Ceres and PCL stay in the .cpp file.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "calib/sweep_assembly.hpp"

namespace sweepmap {

// The rays of one plane seen in one sweep (frame O' of that sweep), and where they came from.
struct LidarPlaneRays {
  std::string source;  // e.g. "room.lcmlog sweep 3 plane 2"
  std::vector<SweepRay> rays;
};

struct PlaneSegmentationOptions {
  double voxel_m = 0.05;            // RANSAC on the voxel-downsampled cloud
  double ransac_distance_m = 0.03;  // RANSAC inlier threshold
  double assign_distance_m = 0.05;  // a ray's range within this of a plane's crossing...
  double edge_margin_m = 0.15;      // ...and no other plane crossing the ray within this of it
  int max_planes = 8;
  int min_inliers = 300;          // after downsampling
  int max_rays_per_plane = 5000;  // evenly strided (time order: spread over the sweep)
  // A ray is dropped when a ray within this many beams and scans of it (a valid one) is not
  // of its plane: depth edges (a door's jamb, a table's edge, a person's outline, mixed
  // pixels) are not the plane, yet their first millimetres pass the gate. 0: kept.
  int depth_edge_rays = 0;
};

// Each ray's scan and beam: those forEachSweepRay recorded (SweepRay::scan, beam); for rays
// made without them, a new scan where theta stops increasing and the beam from theta in steps
// of the smallest step between neighbouring rays (which joins two scans when the first's last
// rays and the second's first rays gave no return).
std::vector<std::pair<long, long>> scanBeamOf(const std::vector<SweepRay>& rays);

// The planes of one sweep: `points_Op` the cloud assembled with the nominal offset, `rays`
// its rays in the same order (forEachSweepRay). A ray belongs to the plane whose crossing
// along the ray its range is within assign_distance_m of, unless another plane crosses the
// ray within edge_margin_m of that crossing (edges, corners) or it lies within
// depth_edge_rays of a ray of no or another plane. Planes with fewer than 3 rays are dropped.
std::vector<LidarPlaneRays> segmentSweepPlanes(const std::vector<Eigen::Vector3f>& points_Op,
                                               const std::vector<SweepRay>& rays,
                                               const PlaneSegmentationOptions& options,
                                               const std::string& source);

// Every n-th of the plane's rays, n the smallest that leaves at most `max_rays` (0: all kept).
void stridePlaneRays(size_t max_rays, LidarPlaneRays* plane);

// A ray placed with the offset t [mm]: Rz(phi) (t + R_L r (0, sin theta, cos theta)) [mm],
// R_L the scan plane's tilt and mirror offset (rotating::lidarRotation; I: the paper's model).
Eigen::Vector3d placeRayMm(const SweepRay& ray, const Eigen::Vector3d& offset_mm,
                           const Eigen::Matrix3d& R_L = Eigen::Matrix3d::Identity());

struct LidarAxisOffsetOptions {
  Eigen::Vector3d initial_offset_mm{13.9, 0.0, 0.0};  // the rig's nominal t_L^O'
  // The rig's scan-plane tilt and mirror offset (rotating::lidarRotation), held: the rest of
  // the rig as its file says.
  Eigen::Matrix3d lidar_rotation = Eigen::Matrix3d::Identity();
  bool estimate_y = false;  // y is not in the rig's model: estimated only when asked
  // Cauchy loss scale; 0: 2.3849 (95 % efficiency) x the residuals' robust sigma (MAD) at
  // the start.
  double cauchy_scale_mm = 0.0;
  int reweightings = 3;  // solves, each with the weights of the previous solution
  int max_iterations = 50;
  double max_sigma_mm = 0.5;  // a larger sigma of x: not determined
  // Components that move the points off their planes by less than this [mm RMS per mm] once
  // the planes have adjusted are not observable (z: ~1e-16 always; x, y: ~0.3-0.5 on a
  // room's walls, ~1e-5 on floor and ceiling alone, from their normals' noise).
  double min_observability = 1e-3;
  double wall_max_normal_z = 0.1;  // planes with |n_z| <= this are walls (parallel to the axis)
};

struct LidarFittedPlane {
  std::string source;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit, frame O' of its sweep
  double distance_mm = 0.0;                          // normal . p = distance
  size_t rays = 0;
  bool wall = false;                               // parallel to the axis
  double rms_before_mm = 0.0, rms_after_mm = 0.0;  // least-squares plane with each offset
};

struct LidarAxisOffsetResult {
  Eigen::Vector3d offset_mm = Eigen::Vector3d::Zero();  // z (and y unless asked) as given
  double sigma_x_mm = std::numeric_limits<double>::quiet_NaN();
  double sigma_y_mm = std::numeric_limits<double>::quiet_NaN();
  bool y_estimated = false;
  bool observable = true;  // x determined by the planes
  // Per component x, y, z: the RMS distance [mm] by which 1 mm of it moves the points off
  // their planes once every plane has adjusted (0: the planes absorb it entirely).
  Eigen::Vector3d observability = Eigen::Vector3d::Zero();
  double smallest_singular_value = 0.0;  // of the estimated components, jointly, scaled
  std::vector<std::string> warnings;
  std::vector<LidarFittedPlane> planes;
  // RMS point-to-plane distance, each plane refit by least squares to its points placed with
  // the nominal offset (before) and the estimate (after): over every plane, and over the walls.
  double rms_before_mm = 0.0, rms_after_mm = 0.0;
  double wall_rms_before_mm = 0.0, wall_rms_after_mm = 0.0;
  // The same over the walls' inliers (points within the Cauchy scale of their plane at the
  // solution; clutter in front of a wall, a door recess left out): the walls' bending alone
  // where the range noise is small.
  double wall_inlier_rms_before_mm = 0.0, wall_inlier_rms_after_mm = 0.0;
  size_t wall_inliers = 0;
  size_t walls = 0;
  double cauchy_scale_mm = 0.0;
  int iterations = 0;
  bool converged = false;
  size_t residuals = 0;
  double seconds = 0.0;
};

// Throws std::invalid_argument when no plane, or a plane with fewer than 3 rays, is given.
LidarAxisOffsetResult solveLidarAxisOffset(const std::vector<LidarPlaneRays>& planes,
                                           const LidarAxisOffsetOptions& options);

}  // namespace sweepmap
