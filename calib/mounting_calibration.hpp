// Calibration of a 2D lidar's 3-axis mounting error on a moving base (rig B, Miao 2022
// section 4.2, Eq. 15-17): the car drives a path that shows the same surfaces twice (a
// circle: the vertical scan plane sweeps every direction once with each side of the
// scan), and the mounting error (gamma about body x, beta about y, alpha about z) is the
// one under which the two passes agree.
//
// Two methods on the same data:
//  - kPaperPoints (the paper's): corresponding points of the two passes, found
//    automatically (the edge points of the calibration target, a board in front of a
//    farther background, in every scan; paired mutually nearest across the passes, not
//    hand picks), and Levenberg-Marquardt on the sum of their squared distances (Eq. 15-17);
//  - kPointToPlane (ours): Ceres over all overlapping points of the two passes, each
//    point against the local plane the other pass sees there, with a robust loss;
//    optionally the lidar-to-odometry time offset as a fourth parameter.
//
// Transport-free and PCL/Ceres-free in this header.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "calib/world_assembly.hpp"
#include "core/scan.hpp"

namespace sweepmap {

enum class MountingMethod { kPaperPoints, kPointToPlane };

const char* mountingMethodName(MountingMethod m);  // "paper_points", "point_to_plane"

struct MountingCalibrationOptions {
  MountingMethod method = MountingMethod::kPointToPlane;
  // Two observations of one place belong to different passes when their scans are at
  // least this far apart in time.
  double min_pass_gap_s = 5.0;
  bool estimate_time_offset = false;   // kPointToPlane only: pose time = ray time + offset
  double max_time_offset_s = 0.1;      // bound of the time offset
  double initial_time_offset_s = 0.0;  // start of the time offset's search
  // kPointToPlane only: also estimate a constant world velocity of the track's position error
  // (odometry drifts by millimetres between the passes, and a shift between the passes is
  // what alpha is seen by). Measured on the simulated 60 s circle with the EKF track, seeds
  // 1-5, before the noise weighting and the in-plane neighbours: alpha error -0.58, -1.33,
  // -0.53, 0.93, -1.70 mrad without, -0.15, -1.28, -0.69, 0.67, -1.19 with it. Off by
  // default: a random walk is not a constant drift, and more laps average it down instead.
  bool estimate_track_drift = false;

  // kPointToPlane: the reference solver (Ceres, every neighbour within the patch radius, one
  // thread; 442 s on the 120 s circle) instead of the fast one (calib/overlap_alignment.hpp:
  // the same residuals from k-nearest neighbours in one k-d tree per half of the scan,
  // reweighted Gauss-Newton with analytic Jacobians, on every core). Kept to measure the
  // fast one against (`make bench`) and for the tests that pin its behaviour.
  bool reference_solver = false;
  int threads = 0;                       // fast solver: 0 = every core (same result)
  std::function<void(double)> progress;  // fast solver: fraction done (may be empty)

  // Shared by both methods.
  bool opposite_sides_only = true;  // the other pass = the other half of the scan (left/right)
  double min_range_m = 0.3;         // closer rays are not used as query/edge points
  int max_outer_iterations = 8;     // correspondence searches (ICP-like outer loop)
  int max_solver_iterations = 50;   // Ceres iterations per outer iteration
  double convergence_rad = 1e-6;    // stop when no angle moves more than this

  // kPointToPlane.
  // Every ray enters the overlap cloud and every second one is a query: alpha is seen only
  // by a shift of 2R alpha between the passes, so it needs all the data (measured on the
  // simulated circle, truth track: the estimate's sigma 0.55 mrad in alpha with every 2nd
  // ray and every 4th query, 0.27 mrad with these).
  int ray_stride = 1;    // every n-th ray of a scan enters the overlap cloud
  int query_stride = 2;  // every n-th of those is a query point
  // The residual's neighbours: the other pass's points nearest to the query along the local
  // plane (up to max_neighbours within this radius; the distance along the normal, where the
  // range noise lies, does not choose them).
  double neighbour_radius_m = 0.15;
  double plane_radius_m = 0.2;         // the patch tested for flatness and giving the normal
  double range_noise_fraction = 0.01;  // the lidar's range noise (X4: < 1 %), for the flatness test
  // Fast solver: a ray whose neighbour in the scan differs in range by more than
  // max(min_edge_jump_m, edge_jump_sigmas of the two ranges' noise) is left out: at a depth edge a
  // lidar returns mixed pixels, anywhere between the two surfaces, which no surface explains.
  double edge_jump_sigmas = 4.0;
  double min_edge_jump_m = 0.05;
  // Rays more oblique to the local plane than this are skipped (grazing: the range noise lies
  // mostly in the plane; measured on the simulated circle: 0.1-0.3 mrad less error in beta
  // and alpha at 1.2 rad than with none).
  double max_incidence_rad = 1.2;
  int min_neighbours = 6;  // of the other pass, for a local plane
  int max_neighbours = 12;
  double max_planarity_ratio = 0.2;    // smallest / middle eigenvalue of the neighbours
  bool check_own_plane = true;         // the query's own pass must see the same plane there
  double max_normal_angle_rad = 0.26;  // between the two passes' local planes (15 deg)
  // Each residual divided by its predicted sigma (the range noise of the query and of its
  // neighbours along the normal, and model_sigma_m); the Cauchy loss then acts at
  // loss_scale_sigmas. Without: residuals in metres, loss at loss_scale_m.
  bool noise_weighting = true;
  double model_sigma_m = 0.001;
  double loss_scale_sigmas = 3.0;
  double loss_scale_m = 0.03;
  double trim_noise_sigmas = 4.0;  // after the first round, residuals beyond max(min_trim_m,
  double min_trim_m = 1e-4;        //   this many range-noise sigmas) are dropped
  double trim_sigmas = 0.0;        // > 0: also beyond this many robust sigmas of the last
                                   //   round's residuals (noise-free data; with noise it
                                   //   reinforces the current estimate: off by default)
  int min_correspondences = 200;
  double max_range_m = 100.0;  // farther rays are not used as query points

  // kPaperPoints: the target is a board in front of a farther background (the lab's board
  // in front of its window recess); in a scan it is a run of rays with a range jump to
  // something farther at both ends, this long between its ends.
  double edge_jump_m = 0.15;  // range discontinuity at the board's edges
  double target_min_extent_m = 0.3;
  double target_max_extent_m = 0.8;
  double max_edge_range_m = 4.0;
  double edge_match_m = 0.2;       // first search radius for the same edge point in the other pass
  double edge_match_min_m = 0.05;  // halved each outer iteration down to this
  int min_point_pairs = 4;         // the paper used 4 hand-picked pairs
};

struct MountingCalibrationResult {
  bool ok = false;
  std::string reason;  // why not ok (too few correspondences, no overlap, ...)
  MountingMethod method = MountingMethod::kPointToPlane;
  double gamma_rad = 0.0, beta_rad = 0.0, alpha_rad = 0.0;
  double time_offset_s = 0.0;  // 0 unless estimated
  // The fast solver's 1-sigma uncertainties from its covariance (0: not computed).
  double sigma_gamma_rad = 0.0, sigma_beta_rad = 0.0, sigma_alpha_rad = 0.0;
  double sigma_time_offset_s = 0.0;
  double drift_x_m_s = 0.0, drift_y_m_s = 0.0;  // the track's position drift; 0 unless estimated
  // RMS of the method's residuals [m] at the initial mounting and at the estimate.
  double residual_before_m = 0.0, residual_after_m = 0.0;
  int correspondences = 0;  // point pairs (paper) or point-plane pairs (ours) used
  int iterations = 0;
};

// `scans`: the lidar scans of the drive (Scan2D::utime = first ray); `track`: the car's
// planar poses (the odometry's), covering the scans; `initial`: the nominal rotation, the
// lidar's position and the initial guess of (gamma, beta, alpha), usually zeros.
// Deterministic: the same input gives the same result.
MountingCalibrationResult calibrateMounting(const std::vector<Scan2D>& scans,
                                            const PoseTrack& track, const LidarMounting& initial,
                                            const MountingCalibrationOptions& options);

}  // namespace sweepmap
