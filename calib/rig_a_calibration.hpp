// `sweepmap calib rig` for rig A (rotating_lidar): every parameter of the build that the room
// sweeps make observable, in one Ceres least squares, because the physics couples them:
//  - the plate angle alpha (plate.alpha_deg),
//  - the lidar-to-axis offset x (geometry.lidar_offset_x_mm; Yuan 2021 Eq. 5-6, Zhao 2021),
//  - the scan plane's tilt against the axis (geometry.scan_plane_tilt_deg, about Y_L),
//  - the mirror's angle zero offset (geometry.mirror_offset_deg, about X_L).
//
// A ray (phi, r, theta) of a sweep is p_O' = Rz(phi) ((x, 0, 0) + Ry(tilt) Rx(-mirror) r (0,
// sin theta, cos theta)) and p_O = Rz(phi_s) p_O', phi_s the sweep's attitude (Eq. 8-10).
// Residuals:
//  - every ray of a room wall (the four vertical planes whose normals in O face +-X, +-Y: the
//    rig stands square to the room, as Yuan 2021's calibration assumes) against its wall:
//    normal (cos a_k cos lean, sin a_k cos lean, sin lean) with a_k fixed, lean and distance
//    free per sweep: they fix phi_s and bend with x, tilt and mirror;
//  - every ray of any other plane (floor, ceiling, furniture) against a free plane in O';
//  - per sweep, the plate (calib/plate_model.hpp): its angle beta_s in O', the angle whose
//    sharp-edged model plate disagrees with the fewest of the rays that meet it (fitPlateAgreeing:
//    on a noise-free sweep the model's hits at the true angle are exactly the measured ones, and
//    the few rays a real sweep gets wrong, mixed pixels in the plate's gate, cannot move it as
//    they moved the centroid), against alpha - phi_s. This is the only residual alpha enters,
//    through phi_s. In a half turn each part of the plate is seen from one side of the scan
//    plane, where an offset error turns it like alpha (0.73 deg/mm, correlation 0.99); a full
//    turn (sweep_angle 360) sees it from both sides, where the offset turns the two views
//    opposite ways, and separates them. The plate is placed with the offset at which its two
//    views agree (for the plate only: an error of its height turns them as an offset does).
// The planes' rays leave out depth edges (PlaneSegmentationOptions::depth_edge_rays): a jamb's
// or a table edge's first millimetres pass the plane's gate, and under the Cauchy loss, whose
// scale follows the noise, they leaned the mirror offset.
// Point residuals are in units of their robust sigma with a Cauchy loss; the plate's in units
// of their scatter over the sweeps. Clutter proud of a wall (a whiteboard) is removed after a
// first solve: cells of 0.5 m on the wall whose median residual exceeds the limit.
// The covariance of the four (calib/parameter_information.hpp: J^T J with the sweeps' attitudes
// and planes eliminated, in a fixed order) gives sigma and correlation; an
// unobservable parameter (calib/rig_calibration.hpp's test) is held at the rig's value and the
// problem solved again.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "calib/axis_offset_lidar.hpp"
#include "calib/plate_model.hpp"
#include "calib/rig_calibration.hpp"

namespace sweepmap {

// One sweep's observations: its planes' rays (calib/axis_offset_lidar.hpp segmentSweepPlanes)
// and the rays that meet the plate's surface in the semi-ring region (with the rig's values),
// with their neighbours along their scans (for the mixed pixels at the plate's edges; empty:
// none taken into account).
struct RigASweep {
  std::string source;
  std::vector<LidarPlaneRays> planes;
  std::vector<SweepRay> plate_rays;
  std::vector<PlateRayBeams> plate_beams;
};

struct RigAValues {
  double alpha_deg = 30.0;
  double offset_x_mm = 13.9;
  double tilt_deg = 0.0;
  double mirror_deg = 0.0;
};

struct RigATruth {
  std::optional<double> alpha_deg, offset_x_mm, tilt_deg, mirror_deg;
};

struct RigASolveOptions {
  RigAValues nominal;  // the rig's values: the start, and what an unobservable one keeps
  RigATruth truth;
  PlateModel plate;
  PlateRegion region;
  int min_plate_hits = 30;
  double wall_max_normal_z = 0.1;
  double wall_azimuth_tolerance_deg = 15.0;
  double clutter_cell_m = 0.5;
  double clutter_limit_mm = 8.0;  // |median residual| of a wall cell above this: clutter
  int max_iterations = 100;
  // Observability limits: sigma of alpha [deg], x [mm], tilt [deg], mirror [deg].
  std::vector<double> max_sigma = {0.5, 0.5, 0.05, 0.05};
  // A warning when the walls' cell medians (cells of 0.5 m pooled over the sweeps, 100 rays or
  // more: noise alone scatters them by ~1.5 mm) still scatter by more than this after the fit.
  double systematic_limit_mm = 4.0;
};

// Throws std::invalid_argument when no sweep has planes.
RigCalibration solveRigA(const std::vector<RigASweep>& sweeps, const RigASolveOptions& options);

// The rays of `rays` (a sweep's, forEachSweepRay's order) whose crossing of the plate's surface,
// placed with `values`, lies in the region (the plate's candidates), into sweep->plate_rays,
// and their neighbours along their scans into sweep->plate_beams.
void takePlateCandidates(const std::vector<SweepRay>& rays, const RigAValues& values,
                         const PlateRegion& region, RigASweep* sweep);

}  // namespace sweepmap
