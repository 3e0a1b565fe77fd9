// The fast engine of rig B's calibrations: the same point-to-plane alignment of a drive's
// two passes as calibrateMounting's reference solver (calib/mounting_calibration.hpp), for
// any parameters that move the world points (the mounting, the lever arm, the time offset,
// the odometry's parameters through the track they give), at a fraction of its cost:
//  - two k-d trees per correspondence search, one per half of the scan (the other pass of a
//    point is the other half), built once per search; each query asks for its k nearest,
//    not for every point within the patch radius (thousands on a 4-lap drive);
//  - the residuals, linear in small parameter changes, are formed once per round with
//    analytic Jacobians; the robust (Cauchy) loss is applied by iteratively reweighted
//    Gauss-Newton on the small normal equations, instead of an automatically differentiated
//    solver re-evaluating every residual per iteration;
//  - the local planes come from 4 cm voxel centroids, and the queries whose points fall in
//    one cube of plane_cell_m share theirs (the reference fits every query's own);
//  - the queries are every query_stride-th ray by the ray's index (the reference counts the
//    covered rays, which shift with the time offset);
//  - the queries are processed on all cores in fixed chunks whose results are reduced in
//    chunk order: the result does not depend on the number of threads or their timing.
// With patch_residuals each point is compared with the plane of its patch instead (rig B's
// calib rig). Transport-free; PCL stays in the .cpp.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "calib/mounting_calibration.hpp"

namespace sweepmap {

// One valid lidar ray of the drive.
struct OverlapRay {
  Eigen::Vector3d q;  // R_nominal p_L [m]: the point in the lidar frame, nominally rotated
  int64_t utime;      // the ray's own time
  bool left;          // on the +Y_L half of the scan
  double range_m;
};

constexpr int kMaxOverlapParameters = 16;
using OverlapJacobian = Eigen::Matrix<double, 3, kMaxOverlapParameters>;

// Where each ray lands in the world for the parameters x, and how it moves with them.
class OverlapModel {
 public:
  virtual ~OverlapModel() = default;
  virtual int parameterCount() const = 0;
  // Re-linearises about x (called once per round, before point()).
  virtual void linearise(const Eigen::VectorXd& x) = 0;
  // Ray i's world point at the linearisation point, the unit direction of the ray in the
  // world and dp/dx (columns past parameterCount() zero); false if the track does not cover
  // the ray's time. Thread-safe (const).
  virtual bool point(size_t i, Eigen::Vector3d* p, Eigen::Vector3d* direction,
                     OverlapJacobian* J) const = 0;
  // dp/dx of ray i at `range_m` instead of its measured range (the Jacobian of the point the
  // ray meets its surface at, free of its own range noise); by default the measured one's.
  virtual bool jacobianAtRange(size_t i, double range_m, OverlapJacobian* J) const {
    Eigen::Vector3d p, d;
    (void)range_m;
    return point(i, &p, &d, J);
  }
};

struct OverlapOptions {
  MountingCalibrationOptions base;  // the pass, patch, weighting and trimming settings
  // The local planes (the other pass's, and the one the query lies on) are fitted to the
  // centroids of each half's points in cubes of this size within base.plane_radius_m.
  double plane_voxel_m = 0.04;
  // > 0: the queries whose points fall in one cube of this size (when they are first queries)
  // share their local planes, fitted around the mean of their points; 0: every query fits its
  // own around its point. On rig B's plan drive the fits were about 90 % of a search's time;
  // shared, a third as many (the same estimates within the seeds' spread: results.md, rig B).
  double plane_cell_m = 0.04;
  int plane_neighbours = 48;     // k nearest of the other pass: the residual's neighbours
  int irls_iterations = 12;      // reweighted Gauss-Newton steps per round
  int threads = 0;               // 0: every core; the result is the same for any number
  std::vector<bool> free;        // per parameter: estimated (else held); empty: all
  Eigen::VectorXd lower, upper;  // bounds (empty: none)
  // > 0: the covariance is the cluster-robust (sandwich) one over cubes of this size, never
  // below chi2 times the inverse normal matrix (which counts correlated residuals as
  // independent); 0: that one alone.
  double cluster_m = 0.0;
  // > 0 (with cluster_m): two-way, also over the pairs of time windows of this length that
  // each residual's query and neighbours fall in (the track's error between two stretches of
  // the drive is common to all their residuals, wherever they lie).
  double cluster_s = 0.0;
  // Plane adjustment instead of point-to-plane: the points of each cube of patch_m (both
  // passes' within min_pass_gap_s of the other's, flat to within their range noise) each give
  // one residual against the patch's plane, the plane (offset and tilt) eliminated, so each
  // point's noise enters once. Point-to-plane compares every query with the local plane of
  // the other pass's k nearest points: their noise enters every query that leans on them.
  // Off by default: its covariance holds the range noise, not the EKF track's error (over 15
  // seeds of rig B's plan drive, alpha's sigma 2.1 and the time offset's 1.7 times too small).
  // Rig B's calib rig uses it and widens each sigma to point-to-plane's where that is larger
  // (calib/mobile_rig_calibration.cpp; docs/explanation/results.md, rig B, "Fifteen seeds").
  bool patch_residuals = false;
  double patch_m = 0.25;
  // Rounds whose parameter change is below this re-linearise without a new search.
  double research_change = 2e-4;
  std::function<void(double)> progress;  // fraction of the rounds done (may be empty)
};

struct OverlapResult {
  bool ok = false;
  std::string reason;
  Eigen::VectorXd x;
  Eigen::MatrixXd covariance;  // of x (zero rows/columns for held parameters)
  // The information matrix of every parameter, held ones too (normal matrix / chi2 per dof):
  // what freeing a held one would give, without solving again.
  Eigen::MatrixXd information;
  double residual_before_m = 0.0, residual_after_m = 0.0;  // RMS of the plain residuals
  double chi2_per_dof = 0.0;  // of the weighted residuals after the last round
  int correspondences = 0;
  int rounds = 0;
  int searches = 0;
  int64_t local_planes = 0;  // point-to-plane: the places local planes were fitted at, summed
};

// cov with each row and column i scaled so that its variance is at least variance(i), the
// correlations kept (a covariance that leaves out an error source, widened to one that holds it).
// Rows with cov(i, i) <= 0 (held parameters) and non-finite variances are left as they are;
// variance has cov's size.
Eigen::MatrixXd widenedTo(const Eigen::MatrixXd& cov, const Eigen::VectorXd& variance);

OverlapResult alignOverlap(const std::vector<OverlapRay>& rays, OverlapModel& model,
                           const Eigen::VectorXd& x0, const OverlapOptions& options);

// The valid rays of `scans`, nominally rotated: every o.ray_stride-th of each scan, but those
// at a depth edge (o.edge_jump_sigmas).
std::vector<OverlapRay> overlapRays(const std::vector<Scan2D>& scans,
                                    const Eigen::Vector3d& nominal_rpy_rad,
                                    const MountingCalibrationOptions& o);

// Rig B's model: p_W = T_WB(t + dt) (R(gamma, beta, alpha) q + t_BL + d_lever) - drift (t -
// t_mid), the planar pose from `track` plus, per odometry parameter k, the track's
// sensitivity (track_k - track) / step_k times (x_k - at_k). Parameters, in this order:
// gamma, beta, alpha [rad], time offset [s], drift x, y [m/s], lever arm dx, dy, dz [m],
// then one per sensitivity.
class MobileOverlapModel : public OverlapModel {
 public:
  enum Index {
    kGamma = 0,
    kBeta,
    kAlpha,
    kTimeOffset,
    kDriftX,
    kDriftY,
    kLeverX,
    kLeverY,
    kLeverZ,
    kFirstOdometry
  };
  struct Sensitivity {
    const PoseTrack* track;  // the odometry's poses with parameter k at at_k + step
    double step;
  };
  MobileOverlapModel(const std::vector<OverlapRay>& rays, const PoseTrack& track,
                     const Eigen::Vector3d& t_BL_m, std::vector<Sensitivity> sensitivities = {});
  int parameterCount() const override { return kFirstOdometry + int(sens_.size()); }
  void linearise(const Eigen::VectorXd& x) override;
  bool point(size_t i, Eigen::Vector3d* p, Eigen::Vector3d* direction,
             OverlapJacobian* J) const override;
  bool jacobianAtRange(size_t i, double range_m, OverlapJacobian* J) const override;
  // The base track (re-linearising the odometry: a new track and its sensitivities, about
  // parameters that the caller then takes as x's origin for those entries).
  void setTrack(const PoseTrack& track, std::vector<Sensitivity> sensitivities);

 private:
  struct RayPose {
    double x, y, th, vx, vy, vth;
    bool covered;
  };
  const std::vector<OverlapRay>& rays_;
  const PoseTrack* track_;
  std::vector<Sensitivity> sens_;
  Eigen::Vector3d t_BL_;
  double t_mid_us_ = 0.0;
  Eigen::VectorXd x_;
  Eigen::Matrix3d R_, dR_[3];
  std::vector<RayPose> poses_;
  std::vector<double> dpose_;  // per ray, per sensitivity: d(x, y, th)/d x_k
  // Ray i's point with its lidar-frame point scaled by `scale` (1: as measured).
  bool scaledPoint(size_t i, double scale, Eigen::Vector3d* p, Eigen::Vector3d* direction,
                   OverlapJacobian* J) const;
};

// Least-squares plane (PCA) of pts[0..count): false if they are not flat (the smallest
// eigenvalue above max_ratio times the middle one, or above max_variance). The normal's
// largest component is positive, so results do not depend on the eigen solver's choice.
bool fitPcaPlane(const Eigen::Vector3d* pts, int count, double max_ratio, double max_variance,
                 Eigen::Vector3d* mean, Eigen::Vector3d* normal);

}  // namespace sweepmap
