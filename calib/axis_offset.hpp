// Calibration of a rotating profile sensor's axis offsets from plane constraints (rig C,
// Zhao 2021 section 3): the points of a flat plate seen in m non-parallel poses must each lie
// on a plane.
//
//  - The paper's method as it is: for a candidate (M, N) every pose's points go to frame O_r
//    by Eq. 7, a plane z = Ax + By + C is fitted by least squares (Eq. 8-13), its RMSE of
//    point-to-plane distances taken (Eq. 14) and averaged over the poses (S, Eq. 15); a grid
//    search over an interval (Algorithm 1) keeps the (M, N) of the smallest S.
//  - Ours: one continuous least-squares problem (Ceres) over M, N and every plane (unit
//    normal on the sphere + distance), point-to-plane residuals through the generalised Eq. 7
//    — optionally with the laser plane's tilt and the encoder's zero — then each parameter's
//    standard deviation from the covariance and an observability check of the parameters
//    from the given planes (the reduced information matrix's spectrum).
//  - The encoder zero: turning the whole cloud about the axis leaves every plane a plane, so
//    planes of unknown pose never fix it. It is the turntable's angle against X_r, and X_r is
//    only defined by something on the base: a reference face fixed to it (a fence) whose
//    normal's azimuth is known by construction. That plane's normal is held in the vertical
//    plane of its azimuth; the zero then follows from the data, its sigma the fit's and the
//    construction's together.
//
// Angles of the samples are the encoder's (2 pi counts / cpr), before any encoder zero.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "core/profile_geometry.hpp"

namespace sweepmap {

struct ProfileSample {
  double y_mm = 0.0, z_mm = 0.0;  // profile point (0, y, z)
  double encoder_rad = 0.0;       // 2 pi counts / cpr
};

// The points of the plate in one pose (one sweep), and where they came from.
struct PlanePoints {
  std::string source;  // e.g. "plate.lcmlog sweep 2"
  std::vector<ProfileSample> samples;
};

// Every `stride`-th sample so that at most `max_samples` remain (all if <= 0).
PlanePoints subsample(const PlanePoints& plane, int max_samples);

// Eq. 8-13: z = a x + b y + c by least squares over `points` (frame O_r). Throws
// std::invalid_argument when the points do not determine such a plane.
struct PlaneFitEq13 {
  double a = 0.0, b = 0.0, c = 0.0;
};
PlaneFitEq13 fitPlaneEq13(const std::vector<Eigen::Vector3d>& points);
// Eq. 14: the RMS of the point-to-plane distances d_i = |a x + b y - z + c| / sqrt(a^2+b^2+1).
double planeRmseEq14(const std::vector<Eigen::Vector3d>& points, const PlaneFitEq13& plane);

// Eq. 15: S, the mean over the poses of Eq. 14 after Eq. 13, with the points placed by Eq. 7
// at (M, N). One pass over the points per pose (the plane fit from their moments).
class PlaneRmseObjective {
 public:
  explicit PlaneRmseObjective(const std::vector<PlanePoints>& planes);
  double meanRmse(double m_mm, double n_mm) const;
  size_t samples() const;

 private:
  // Per sample, what Eq. 7 needs: cos, sin of the angle, y cos, y sin, z.
  struct Pre {
    double c, s, yc, ys, z;
  };
  std::vector<std::vector<Pre>> planes_;
  std::vector<Eigen::Vector3d> reference_;  // per pose: subtracted before the moments
};

struct GridSearchOptions {
  double m_min_mm = 110.0, m_max_mm = 130.0;  // the paper's interval (section 4)
  double n_min_mm = 395.0, n_max_mm = 425.0;
  double step_mm = 1.0;  // the paper's 1 mm
};

struct GridSearchResult {
  double m_mm = 0.0, n_mm = 0.0;  // the grid node of the smallest S
  double s_min_mm = 0.0;
  std::vector<double> m_values, n_values;
  std::vector<double> s_mm;  // S at (m_values[i], n_values[j]): s_mm[i * n_values.size() + j]
  double seconds = 0.0;
};

// Algorithm 1 over the interval, both ends included. Throws std::invalid_argument for an
// empty interval or a step <= 0.
GridSearchResult gridSearchAxisOffset(const std::vector<PlanePoints>& planes,
                                      const GridSearchOptions& options);

struct AxisOffsetOptions {
  ProfileGeometry initial;  // the starting point (the rig's nominal geometry)
  bool estimate_tilt = true;
  bool estimate_encoder_zero = false;
  int max_iterations = 100;
  // A parameter whose standard deviation exceeds these is reported as not determined.
  double max_sigma_mm = 0.5;
  double max_sigma_deg = 0.1;
  // Zhao 2021 needs non-parallel planes: when no two fitted normals are this far apart, M and
  // N are reported as not determined (with parallel plates the laser tilt and M trade off;
  // measured on the default simulation: M 0.6 mm off while its sigma said 0.09 mm).
  double min_plane_angle_deg = 5.0;
  // Planes of the base's reference face (indices into the planes, see findReferencePlanes),
  // whose normal leans towards reference_azimuth_rad in O_r by construction. With the encoder
  // zero estimated their normals are held in that azimuth's vertical plane, which fixes it;
  // without any, the zero is not observable (held at its initial value, with a warning).
  std::vector<size_t> reference_planes;
  double reference_azimuth_rad = 0.0;
  // How well construction fixes that azimuth: the zero's error from it, one for one, added in
  // quadrature to the zero's sigma.
  double reference_azimuth_sigma_rad = 0.0;
};

// The planes whose normal, their points placed by `geometry`, lies within `tolerance_rad` of
// the reference face's (leaning `tilt_rad` from vertical towards `azimuth_rad`): the sweeps over
// it. A nominal encoder zero off by e shifts the normal by about e sin(tilt).
std::vector<size_t> findReferencePlanes(const std::vector<PlanePoints>& planes,
                                        const ProfileGeometry& geometry, double azimuth_rad,
                                        double tilt_rad, double tolerance_rad);

struct FittedPlane {
  Eigen::Vector3d normal;  // unit, in O_r
  double distance_mm;      // normal . p = distance
  double rms_mm;           // of its points' residuals
};

struct AxisOffsetResult {
  ProfileGeometry geometry;
  // Standard deviations from the covariance (calib/parameter_information.hpp, scaled by the
  // residuals' variance); NaN where a parameter was not estimated or the covariance is singular.
  double sigma_m_mm = 0.0, sigma_n_mm = 0.0, sigma_tilt_deg = 0.0, sigma_zero_deg = 0.0;
  bool tilt_estimated = false, zero_estimated = false;
  // The zero's sigma from the fit alone (NaN when not estimated); sigma_zero_deg adds the
  // reference face's construction sigma to it.
  double sigma_zero_fit_deg = std::numeric_limits<double>::quiet_NaN();
  // Covariance of (M [mm], N [mm], laser tilt [deg], encoder zero [deg]), scaled like the
  // sigmas; NaN in the rows and columns of a parameter not estimated.
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Constant(std::numeric_limits<double>::quiet_NaN());
  bool observable = true;  // M and N both determined by the planes
  std::vector<std::string> warnings;
  std::vector<FittedPlane> planes;
  // Over every residual; before: the initial geometry (its encoder zero turned to what the
  // reference face shows, when the zero is fitted against one) with each plane fitted to it.
  double rms_before_mm = 0.0, rms_after_mm = 0.0;
  double smallest_singular_value = 0.0;  // of the rig's reduced, column-scaled Jacobian
  double largest_plane_angle_deg = 0.0;  // between any two fitted normals
  int iterations = 0;
  bool converged = false;
  size_t residuals = 0;
  double seconds = 0.0;
};

// Ours. Throws std::invalid_argument when fewer than one pose or a pose with fewer than 3
// samples is given.
AxisOffsetResult solveAxisOffset(const std::vector<PlanePoints>& planes,
                                 const AxisOffsetOptions& options);

}  // namespace sweepmap
