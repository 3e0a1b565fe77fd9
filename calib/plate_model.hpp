// The triangular plate as a solid (rig A): which rays of a sweep it should return, for an
// estimate of its angle that carries no sampling bias.
//
// The ray-plane and centroid estimators (calib/plate.hpp) take the centroid of the plate's
// points as its middle line; the rays sample the plate unevenly (they fan out from a lidar
// centre off the axis, a 2 mm edge face returns some), so that centroid sits a fraction of a
// degree off the middle line, and the calibrated alpha absorbs it: not the physical angle.
// The model estimator compares like with like: the same rays cast at a model of the plate
// (isosceles right triangle, upper surface at height, `thickness` of solid below it whose
// hypotenuse face catches the rays that pass just inside the edge) give a predicted centroid,
// and the plate's angle is the one whose predicted centroid points where the measured one
// does. A lost scan or a dropout removes the ray from both.
//
// The coverage of a ray is smooth (logistic in its distance to each edge, `edge_m` wide): the
// angle is a smooth function of the geometry (Ceres differentiates it numerically).
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "calib/plate.hpp"
#include "core/rig_components.hpp"

namespace sweepmap {

struct PlateModel {
  double height_m = -0.045;  // upper surface, frame O / O'
  double thickness_m = 0.002;
  double hypotenuse_m = 0.112;
  double base_distance_m = 0.05475;
  double edge_m = 0.002;  // width of the coverage's smooth edge
  double range_gate_m = 0.03;
  static PlateModel fromConfig(const PlateConfig& plate);
};

// Smooth coverage in [0, 1] of the ray (origin, unit dir) by the model plate whose middle
// line is at `angle_rad` from X (same frame).
double plateCoverage(const PlateModel& m, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                     double angle_rad);

// The same plate with sharp edges: does the ray (origin, unit dir) end on it? What the rays of
// a real (or simulated) plate do: each is in or out.
bool plateCovers(const PlateModel& m, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                 double angle_rad);

struct PlateModelFit {
  bool found = false;
  double angle_rad = 0.0;     // the plate's middle line in the rays' frame
  int hits = 0;               // rays whose range agrees with the upper surface
  double residual_rad = 0.0;  // measured minus predicted centroid direction at angle_rad
  std::string reason;
};

// The measured-minus-predicted centroid direction [rad] with the plate at `angle_rad`: the
// measured centroid is of the upper-surface crossings of the rays whose range agrees with it
// (within the gate), the predicted one of every ray's crossing weighted by its coverage.
// nullopt when no ray agrees or none is covered.
// `hits`, if given, says which rays count as measured hits (fixed, e.g. for a solver that
// moves the rays: the gate then cannot flip a ray in or out between two evaluations).
std::optional<double> plateCentroidMismatch(const PlateModel& m, const std::vector<PlateRay>& rays,
                                            double angle_rad,
                                            const std::vector<char>* hits = nullptr);
// Which rays' ranges agree with their crossing of the upper surface (within the gate).
std::vector<char> plateHits(const PlateModel& m, const std::vector<PlateRay>& rays);

// A plate ray's neighbours along its scan: the range [m] of the beam next to it before (side 0)
// and after it (side 1), 0 where there is no return (or the scan ends); and that beam's index
// among the plate rays, -1 if it is not one.
struct PlateRayBeams {
  std::array<float, 2> range{};
  std::array<int, 2> next{-1, -1};
};

// The rays that count as measured hits, with weights: plateHits' rays (1), less those whose
// side of a depth edge is not knowable (-1, in neither centroid). A lidar's ray at a depth edge
// may return a range anywhere between the plate's and the background's (a mixed pixel): the
// plate's last ray may fall out of the gate, or the background's first read between. Behind
// the plate's edges the background is the floor at grazing incidence, whose range climbs by
// tens of millimetres a beam, so no range tells a mixed pixel from the background's first ray:
// the ray past a run of hits along a scan is the plate's last or the background's first, and
// is left out whatever its range. So is a ray that is not a hit beside a beam that gave no
// return (the plate's hypotenuse face drops glancing rays; the ray may be the plate's, mixed).
// A rule that judged mixed pixels by their range against the background 3 beams out counted
// floor rays 2 m away as the plate's and turned seed 3 of the plan's recording by -0.024 deg.
// What is left: a background's mixed pixel within the plate's gate counts as a hit (~1 in 60
// edges). `beams` empty: plateHits' rays alone.
std::vector<double> plateHitWeights(const PlateModel& m, const std::vector<PlateRay>& rays,
                                    const std::vector<PlateRayBeams>& beams);

// The agreeing estimator: the angle whose sharp plate (plateCovers) disagrees with the fewest
// measured rays (`weights` > 0 a hit, 0 not, < 0 in neither): the middle of the widest range of
// angles with the fewest (when the fewest come in separate ranges, the widest of them, never
// the gap between), searched within `window_rad` of `start_rad` (re-centred while that range
// lies at its end). Each ray is in or out, and a few are wrong whatever the angle
// (a background's mixed pixel in the plate's gate, ~1 in 60 edges; a mixed pixel where a scan clips
// a corner of the plate): the centroid moves with each of them, and the sampled centroid's
// mismatch, flat where no counted ray flips (the ray past each run of hits is in neither), turned 4
// spurious hits of one view's 4 900 into a 0.14 deg error (seed 3 of the plan's recording).
// Counting disagreements is what the rays say when a few of them can be wrong: one spurious hit
// cannot win against the rays the plate's edge would flip to reach it. nullopt when no counted ray
// is a hit; throws std::invalid_argument when `weights` and `rays` differ in size.
std::optional<double> fitPlateAgreeing(const PlateModel& m, const std::vector<PlateRay>& rays,
                                       const std::vector<double>& weights, double start_rad,
                                       double window_rad = 0.01);

// The angle whose predicted centroid points where the measured one does (fixed-point
// iteration from the measured centroid's direction). Not found with fewer than `min_hits`.
PlateModelFit fitPlateModel(const PlateModel& m, const std::vector<PlateRay>& rays, int min_hits);

// The sampled estimator: the smooth edge stands for the mean over where the edges fall between
// the rays, but a sweep's rays are one fixed grid (scans 0.56 deg apart on a full turn, rays
// 0.25 deg apart), whose hits along the edges are what they are: the smooth prediction misses
// the measured centroid by up to 0.025 deg per sweep even without noise. With sharp edges the
// model's hits at the true angle are exactly the measured ones (noise-free), so the predicted
// centroid equals the measured one on an interval of angles around it.
// plateSampledMismatch: plateCentroidMismatch with plateCovers' 0 / 1 coverage (a step function
// of the angle, non-increasing).
// `weights`: each ray's weight in the measured centroid (plateHitWeights; < 0: in neither).
std::optional<double> plateSampledMismatch(const PlateModel& m, const std::vector<PlateRay>& rays,
                                           double angle_rad, const std::vector<double>& weights);
// fitPlateSampled: where plateSampledMismatch changes sign, by bisection from `start_rad` (e.g.
// fitPlateModel's angle): the middle of the interval where it is 0, or its jump through 0.
// nullopt when no ray is covered or no sign change lies within ~1 rad.
std::optional<double> fitPlateSampled(const PlateModel& m, const std::vector<PlateRay>& rays,
                                      const std::vector<double>& weights, double start_rad);

}  // namespace sweepmap
