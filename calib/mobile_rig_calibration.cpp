// Rig B's joint calibration: see calib/mobile_rig_calibration.hpp.
#include "calib/mobile_rig_calibration.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <set>
#include <utility>

#include "calib/overlap_alignment.hpp"
#include "calib/room_planes.hpp"

namespace sweepmap {
namespace {

using M = MobileOverlapModel;
// The joint vector's one odometry entry: the change e of the wheels' common scale (radii and
// track together, relative) from the odometry run's.
constexpr int kScale = M::kFirstOdometry, kParameters = M::kFirstOdometry + 1;

// A parameter is observable when the drive determines it better than this (1 sigma): beyond,
// it is held at nominal and reported unobservable.
double observabilityBound(int k) {
  switch (k) {
    case M::kGamma:
    case M::kBeta:
    case M::kAlpha:
      return 3e-3;  // rad
    case M::kTimeOffset:
      return 0.02;  // s
    case M::kLeverX:
    case M::kLeverY:
    case M::kLeverZ:
      return 0.01;  // m
    case kScale:
      return 3e-3;  // relative (1 mm in 0.3 m of a wheel's turn)
    default:
      return 0.0;
  }
}
// The residuals err together within about a plane patch (they share the other pass's planes)
// and along a wall: their covariance is the cluster-robust one over cubes of this size.
constexpr double kClusterM = 0.5;
// ... and between the same two stretches of the drive (the track's error between them: the
// encoders' noise, a slip, the gyro's drift), wherever they lie: two-way with time windows of
// this length (0.6 m at the plan's 0.2 m/s, about a cube).
constexpr double kClusterS = 3.0;

MobileWheelParameters scaled(MobileWheelParameters w, double factor) {
  w.radius_left_m *= factor;
  w.radius_right_m *= factor;
  w.wheel_distance_m *= factor;
  return w;
}

// The odometry at the wheels w, and with their common scale moved by `step`: the model's
// sensitivity to e.
struct Sensitivities {
  MobileOdometryRun base;
  PoseTrack moved;
  double step = 1e-3;
};

void runOdometry(const MobileRigCalibrationInput& in, const MobileWheelParameters& w,
                 Sensitivities* s) {
  s->base = in.odometry(w);
  s->moved = in.odometry(scaled(w, 1.0 + s->step)).track;
}

// The solver's options over `free`, with patch residuals or point-to-plane.
OverlapOptions solverOptions(const std::vector<bool>& free, const MobileRigCalibrationInput& in,
                             bool patches) {
  OverlapOptions oo;
  oo.patch_residuals = patches;
  oo.base = in.options;
  oo.free = free;
  oo.lower = Eigen::VectorXd::Constant(kParameters, -1e300);
  oo.upper = Eigen::VectorXd::Constant(kParameters, 1e300);
  oo.lower(M::kTimeOffset) = -in.options.max_time_offset_s;
  oo.upper(M::kTimeOffset) = in.options.max_time_offset_s;
  oo.threads = in.options.threads;
  oo.cluster_m = kClusterM;
  oo.cluster_s = kClusterS;
  return oo;
}

// One joint solve from x over `free`; the held parameters keep their values in x. The residuals
// are each point's distance from its patch's plane (the plane adjustment:
// OverlapOptions::patch_residuals), which counts each point's range noise once; point-to-plane
// counts the other pass's noise again in every query that leans on it. Over 15 seeds of calib
// plan's drive the patches put beta within 0.3 mrad on 12 and alpha on 15, point-to-plane on 9
// and 10 (docs/explanation/results.md, rig B, "Fifteen seeds").
OverlapResult solve(const std::vector<OverlapRay>& rays, M& model, const Eigen::VectorXd& x,
                    const std::vector<bool>& free, const MobileRigCalibrationInput& in) {
  return alignOverlap(rays, model, x, solverOptions(free, in, true));
}

// The patches' covariance holds the range noise but not the EKF track's error, which moves
// every point of a stretch of the drive alike, as alpha and the time offset do: over the 15
// seeds their sigmas were 2.1 and 1.7 times too small. Point-to-plane's two-way clustered
// covariance takes that error in (its full runs' sigmas honest on the same seeds, mean z^2
// 0.75-1.40), and counts the other pass's noise more than once. One round of it from the
// patches' solution (one search, its first round untrimmed, the Cauchy loss alone against
// outliers) gives each parameter's sigma; each becomes the larger of the two, the patches'
// correlations kept. Measured so on the 15 seeds: mean z^2 0.03-0.83, the largest 1.5 sigma,
// wide for beta and gamma. Returns why not, if point-to-plane finds too little.
std::string widenByPointToPlane(const std::vector<OverlapRay>& rays, M& model,
                                const MobileRigCalibrationInput& in, const std::vector<bool>& free,
                                OverlapResult* r) {
  OverlapOptions oo = solverOptions(free, in, false);
  oo.base.max_outer_iterations = 1;
  const OverlapResult p2p = alignOverlap(rays, model, r->x, oo);
  if (!p2p.ok) return p2p.reason;
  r->covariance = widenedTo(r->covariance, p2p.covariance.diagonal());
  return "";
}

// The covariance of the parameters in `set` from the information matrix; false if singular.
bool covarianceOf(const Eigen::MatrixXd& info, const std::vector<int>& set, Eigen::MatrixXd* cov) {
  const int F = int(set.size());
  Eigen::MatrixXd H(F, F);
  for (int i = 0; i < F; ++i) {
    for (int j = 0; j < F; ++j) H(i, j) = info(set[size_t(i)], set[size_t(j)]);
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(H);
  if (!lu.isInvertible()) return false;
  *cov = lu.inverse();
  return true;
}

// Stated order: the mounting angles first (always observable on a drive that sees the same
// surfaces twice), then the wheels' scale, the lever arm and the time offset in turn, each kept
// when the drive determines it within its bound without more than doubling the sigma of any
// parameter already kept (judged on the information matrix of the angles' solution, no solve per
// candidate). Then one joint solve over the kept ones.
OverlapResult solveObservable(const std::vector<OverlapRay>& rays, M& model,
                              const Eigen::VectorXd& x, const MobileRigCalibrationInput& in,
                              std::vector<bool>* free) {
  std::vector<bool> angles(size_t(kParameters), false);
  for (int k : {M::kGamma, M::kBeta, M::kAlpha}) angles[size_t(k)] = true;
  const OverlapResult first = solve(rays, model, x, angles, in);
  if (!first.ok) return first;
  std::vector<int> kept = {M::kGamma, M::kBeta, M::kAlpha};
  const auto keepOnly = [&] {
    std::fill(free->begin(), free->end(), false);
    for (int k : kept) (*free)[size_t(k)] = true;
  };
  Eigen::MatrixXd cov;
  if (!covarianceOf(first.information, kept, &cov)) {
    keepOnly();
    return first;
  }
  const int order[] = {kScale, M::kLeverY, M::kLeverX, M::kLeverZ, M::kTimeOffset};
  for (int k : order) {
    if (!(*free)[size_t(k)]) continue;
    std::vector<int> trial = kept;
    trial.push_back(k);
    Eigen::MatrixXd c;
    bool ok = covarianceOf(first.information, trial, &c) &&
              std::sqrt(std::max(0.0, c(int(trial.size()) - 1, int(trial.size()) - 1))) <=
                  observabilityBound(k);
    for (size_t i = 0; ok && i < kept.size(); ++i) {
      ok = c(int(i), int(i)) <= 4.0 * cov(int(i), int(i));
    }
    if (ok) {
      kept = trial;
      cov = c;
    }
  }
  keepOnly();
  return solve(rays, model, first.x, *free, in);
}

// Everything the steps found.
struct Solution {
  Eigen::VectorXd x;  // the joint vector (its scale entry folded into w: zero)
  OverlapResult r;    // the last joint solve (its covariance: of the last pass's change)
  std::vector<bool> free;
  MobileWheelParameters w;  // the calibrated wheels
  WheelGyroResult wg;       // step 1
  std::vector<CalibMeasure> room;
  bool floor_z = false;  // the lever arm's z from the floor (the passes cannot see it)
  double floor_z_sigma = 0.0;
  std::vector<std::string> room_warnings;
  std::string not_widened;  // why the sigmas were not widened to point-to-plane's ("": they were)
  bool wheels = false;      // step 1 determined k_L and k_R
  double rms_before = 0.0;
};

// Reported parameters, in this order.
enum Reported { kRGamma, kRBeta, kRAlpha, kRX, kRY, kRZ, kRLeft, kRRight, kRTrack, kRTime, kRBias };
constexpr int kReported = 11;

// The reported parameters' covariance: the joint solve's and step 1's blocks (independent
// data) through the Jacobian of what each measures. The lidar measures the distance driven,
// the mean radius rm = rm0 (1 + e), whatever k is; the gyro the k = r / T. So
// r_L = 2 rm k_L / (k_L + k_R), r_R = 2 rm k_R / (k_L + k_R), T = 2 rm / (k_L + k_R).
Eigen::MatrixXd reportedCovariance(const Solution& s) {
  const int O = kParameters;  // the joint vector, then (k_L, k_R, b)
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(O + 3, O + 3);
  C.topLeftCorner(O, O) = s.r.covariance;
  if (s.wheels) C.bottomRightCorner(3, 3) = s.wg.covariance;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(kReported, O + 3);
  const int from[] = {M::kGamma, M::kBeta, M::kAlpha, M::kLeverX, M::kLeverY, M::kLeverZ};
  for (int i = 0; i < 6; ++i) J(i, from[i]) = 1.0;
  const double T = s.w.wheel_distance_m, rl = s.w.radius_left_m, rr = s.w.radius_right_m;
  const double kl = s.wg.x(0), kr = s.wg.x(1), ks = kl + kr;
  J(kRLeft, kScale) = rl;
  J(kRRight, kScale) = rr;
  J(kRTrack, kScale) = T;
  if (s.wheels) {
    J(kRLeft, O) = rl * kr / (kl * ks);
    J(kRLeft, O + 1) = -rl / ks;
    J(kRRight, O) = -rr / ks;
    J(kRRight, O + 1) = rr * kl / (kr * ks);
    J(kRTrack, O) = J(kRTrack, O + 1) = -T / ks;
  }
  J(kRTime, M::kTimeOffset) = -1.0;
  J(kRBias, O + 2) = 1.0;
  Eigen::MatrixXd cov = J * C * J.transpose();
  if (s.floor_z) cov(kRZ, kRZ) += s.floor_z_sigma * s.floor_z_sigma;
  return cov;
}

void addWarnings(const MobileRigCalibrationInput& in, const Solution& s, RigCalibration* out) {
  for (const CalibParameter& p : out->parameters) {
    if (!p.observable)
      out->warnings.push_back(p.key + ": not observable from these logs (" + p.note +
                              "); left at the rig file's");
  }
  if (!s.wheels) out->warnings.push_back("wheels against the gyro: " + s.wg.reason);
  if (s.wheels && s.wg.trimmed > 0) {
    out->warnings.push_back("wheels against the gyro: " + std::to_string(s.wg.trimmed) + " of " +
                            std::to_string(s.wg.trimmed + s.wg.rows) +
                            " windows disagreed beyond the noise (wheel slip) and were left out");
  }
  if (!s.not_widened.empty()) {
    out->warnings.push_back(
        "the sigmas are the plane patches' alone (point-to-plane at their solution: " +
        s.not_widened + "): alpha's and the time offset's may be up to twice too small");
  }
  if (s.r.chi2_per_dof > 4.0) {
    out->warnings.push_back("the residuals are larger than the lidar's noise explains (chi2/dof " +
                            std::to_string(s.r.chi2_per_dof) +
                            "): an error the model does not have (moving objects, "
                            "a wrong noise figure, slip) may bias the result");
  }
  if (s.free[M::kTimeOffset] &&
      std::abs(s.x(M::kTimeOffset)) >= 0.99 * in.options.max_time_offset_s) {
    out->warnings.push_back("lidar.time_offset_s ran to its bound: the drive does not observe it");
  }
}

RigCalibration report(const MobileRigCalibrationInput& in, const Solution& s) {
  RigCalibration out;
  const LidarMounting& n = in.nominal;
  const MobileWheelParameters& w0 = in.wheels;
  const Eigen::VectorXd& x = s.x;
  const bool scale = s.wheels && s.free[size_t(kScale)];
  struct Row {
    const char* key;
    const char* unit;
    double value, nominal;
    bool observable;
  };
  const Row rows[kReported] = {
      {"mounting.gamma_rad", "rad", x(M::kGamma), n.gamma_rad, s.free[M::kGamma]},
      {"mounting.beta_rad", "rad", x(M::kBeta), n.beta_rad, s.free[M::kBeta]},
      {"mounting.alpha_rad", "rad", x(M::kAlpha), n.alpha_rad, s.free[M::kAlpha]},
      {"mounting.x_m", "m", n.t_BL_m.x() + x(M::kLeverX), n.t_BL_m.x(), s.free[M::kLeverX]},
      {"mounting.y_m", "m", n.t_BL_m.y() + x(M::kLeverY), n.t_BL_m.y(), s.free[M::kLeverY]},
      {"mounting.z_m", "m", n.t_BL_m.z() + x(M::kLeverZ), n.t_BL_m.z(),
       s.free[M::kLeverZ] || s.floor_z},
      {"odometry.wheel_radius_m", "m", s.w.radius_left_m, w0.radius_left_m, scale},
      {"odometry.wheel_radius_right_m", "m", s.w.radius_right_m, w0.radius_right_m, scale},
      {"odometry.wheel_distance_m", "m", s.w.wheel_distance_m, w0.wheel_distance_m, scale},
      {"lidar.time_offset_s", "s", in.time_offset_s - x(M::kTimeOffset), in.time_offset_s,
       s.free[M::kTimeOffset]},
      {"odometry.gyro_bias_rad_s", "rad/s", s.wg.x(2), in.gyro_bias_rad_s, s.wheels},
  };
  const Eigen::MatrixXd cov = reportedCovariance(s);
  for (int i = 0; i < kReported; ++i) {
    const Row& row = rows[i];
    CalibParameter p;
    p.key = row.key;
    p.unit = row.unit;
    p.observable = row.observable;
    p.value = p.observable ? row.value : row.nominal;
    p.nominal = row.nominal;
    p.sigma = p.observable ? std::sqrt(std::max(0.0, cov(i, i))) : 0.0;
    if (!p.observable)
      p.note = i >= kRLeft && i <= kRTrack && !s.wheels
                   ? "the gyro against the wheels did not determine them (turns both ways, "
                     "straights and stops needed)"
               : i >= kRLeft && i <= kRTrack ? "the lidar did not determine the distance driven"
               : i == kRBias                 ? "the wheels against the gyro failed"
                                             : "its sigma exceeds its bound on this drive";
    const auto t = in.truth.find(p.key);
    if (t != in.truth.end()) p.truth = t->second;
    out.parameters.push_back(p);
  }
  Eigen::MatrixXd shown = cov;
  for (int i = 0; i < kReported; ++i) {
    if (!out.parameters[size_t(i)].observable) shown.row(i).setZero(), shown.col(i).setZero();
  }
  out.correlation = correlationOf(shown);
  out.correlation.diagonal().setOnes();
  out.rms_before = s.rms_before;
  out.rms_after = s.r.residual_after_m;
  out.measures = s.room;
  addWarnings(in, s, &out);
  out.warnings.insert(out.warnings.end(), s.room_warnings.begin(), s.room_warnings.end());
  return out;
}

// The cloud the model places at its linearisation point x, and where the lidar was for each
// point (the point less its ray).
struct PlacedCloud {
  std::vector<Eigen::Vector3f> points, origins;
};
PlacedCloud cloudAt(const std::vector<OverlapRay>& rays, M& model, const Eigen::VectorXd& x) {
  model.linearise(x);
  PlacedCloud cloud;
  cloud.points.reserve(rays.size());
  cloud.origins.reserve(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    Eigen::Vector3d p, d;
    if (!model.point(i, &p, &d, nullptr)) continue;
    cloud.points.push_back(p.cast<float>());
    cloud.origins.push_back((p - rays[i].range_m * d).cast<float>());
  }
  return cloud;
}

// The lidar's range noise and limit, for the room's planes (calib/room_planes.hpp).
RangeNoise rangeNoiseOf(const MobileRigCalibrationInput& in) {
  RangeNoise noise;
  noise.fraction = in.options.range_noise_fraction;
  for (const Scan2D& s : in.scans) noise.range_max_m = std::max(noise.range_max_m, s.range_max_m);
  return noise;
}

// The points of c (with their ray origins) for which keep(point, origin) holds.
template <class Keep>
PlacedCloud filtered(const PlacedCloud& c, Keep keep) {
  PlacedCloud out;
  for (size_t i = 0; i < c.points.size(); ++i) {
    if (!keep(c.points[i], c.origins[i])) continue;
    out.points.push_back(c.points[i]);
    out.origins.push_back(c.origins[i]);
  }
  return out;
}

// The cloud without the floor near anything standing on it: the (x, y) cells of
// kStructureCellM holding a point between 2 and 30 cm above the floor, and their neighbours.
// The foot of a wall or a table leg lies within the floor's window (3 sigma, 9 mm) and all of
// it above the floor.
constexpr double kStructureCellM = 0.1;
PlacedCloud awayFromStructure(const PlacedCloud& c) {
  const auto cellOf = [](const Eigen::Vector3f& p) {
    return std::make_pair(int(std::floor(p.x() / kStructureCellM)),
                          int(std::floor(p.y() / kStructureCellM)));
  };
  std::set<std::pair<int, int>> standing;
  for (const Eigen::Vector3f& p : c.points) {
    if (p.z() > 0.02f && p.z() < 0.3f) standing.insert(cellOf(p));
  }
  return filtered(c, [&](const Eigen::Vector3f& p, const Eigen::Vector3f&) {
    const auto [x, y] = cellOf(p);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        if (standing.count({x + dx, y + dy}) > 0) return false;
      }
    }
    return true;
  });
}

// The rays of c within kFloorMaxIncidenceRad of the normal n. Rays nearer grazing are
// left out. Between two neighbouring rays (the X4's 0.5 deg) their ranges on the floor differ
// by more than 9 mm at 0.3 m height: 50 mm at 77 deg. A return there may be a mixed pixel
// between the two ranges, and one beyond the floor lies below it, inside its 3 sigma window.
// The depth-edge filter's 4 sigma does not see such gaps at 1-2 m. On 15 seeds of calib plan's
// drive the floor then stood 0.02-0.036 mm low, 3.2-4.7 sigma on three seeds. With this
// limit the lever arm's z is within 0.022 mm, at most 2.5 sigma. (The step is the X4's; a lidar
// of finer steps has smaller gaps at the same angle, so the limit only costs it some rays.)
constexpr double kFloorMaxIncidenceRad = 60.0 * M_PI / 180.0;
PlacedCloud steepRays(const PlacedCloud& c, const Eigen::Vector3d& n) {
  const Eigen::Vector3f nf = n.cast<float>();
  const float min_cos = float(std::cos(kFloorMaxIncidenceRad));
  return filtered(c, [&](const Eigen::Vector3f& p, const Eigen::Vector3f& origin) {
    return std::abs((p - origin).normalized().dot(nf)) >= min_cos;
  });
}

// The lidar's height from the floor: the body frame's xOy plane is the floor, so the floor
// the cloud shows at height f says the lever arm's z is off by -f. The floor refined against
// the range noise, away from what stands on it (the RANSAC plane's 30 mm window held the foot
// of every wall: -0.13 mm on every seed; a 3 sigma window alone still -0.01 to -0.02 mm). Its
// sigma: the refined plane's offset_sigma at its centroid (cluster-robust over in-plane cells:
// the points of a cell err together, the same passes, the same attitude errors of the track).
struct FloorLever {
  bool ok = false;
  double dz = 0.0, sigma = 0.0;
};
FloorLever leverFromFloor(const PlacedCloud& all, const RoomPlanes& planes,
                          const RangeNoise& noise) {
  FloorLever f;
  if (!planes.floor || planes.floor->inlier_indices.size() < 100) return f;
  const PlacedCloud cloud = steepRays(awayFromStructure(all), planes.floor->normal);
  // No clutter search: what stands on the floor is taken away above.
  const RefinedPlane floor = refinePlane(cloud.points, cloud.origins, *planes.floor, noise);
  // Its sigma is cluster-robust over the cells: too few of them give no sigma to trust.
  f.ok = floor.ok && floor.offset_cells > 10;
  if (!f.ok) return f;
  f.dz = -floor.centroid.z();
  f.sigma = floor.offset_sigma;
  return f;
}

// The room's size in the calibrated cloud.
std::vector<CalibMeasure> roomMeasures(const PlacedCloud& cloud, const RoomPlanes& planes,
                                       const RangeNoise& noise,
                                       const std::optional<Eigen::Vector3d>& truth,
                                       std::vector<std::string>* warnings) {
  const RoomDims dims = refinedRoomDims(planes, cloud.points, cloud.origins, noise);
  std::vector<CalibMeasure> out;
  const std::optional<double> L[3] = {dims.L1, dims.L2, dims.L3};
  // The height without a sigma: the mixed pixels the depth-edge filter keeps far from the lidar
  // lie beyond the floor and the ceiling alike and make it 0.36-0.46 mm tall on every seed of
  // calib plan's drive, 4-5 times its noise's sigma (docs/explanation/results.md, rig B).
  const double sigma[3] = {dims.L1_sigma, dims.L2_sigma, 0.0};
  const char* keys[3] = {"room.length_m", "room.width_m", "room.height_m"};
  for (int k = 0; k < 3; ++k) {
    if (!L[k]) continue;
    CalibMeasure m{keys[k], *L[k], "m", std::nullopt, std::nullopt};
    if (sigma[k] > 0.0) m.sigma = sigma[k];
    if (truth) m.truth = (*truth)(k);
    out.push_back(m);
  }
  if (out.size() < 3) warnings->push_back("the room's size not measured: " + planes.reason);
  return out;
}

// After a pass's joint solve: the floor gives the lever arm's z (which the passes cannot see:
// it moves every point alike); after the last pass, the room's size too.
void floorAndRoom(const MobileRigCalibrationInput& in, const std::vector<OverlapRay>& rays,
                  M& model, bool last, Solution* s) {
  const PlacedCloud cloud = cloudAt(rays, model, s->r.x);
  // A drive in one end of the room sees the far wall thinly, and the furniture's and the
  // door's planes come first: more and smaller planes than the defaults (a loop's).
  WallExtractionOptions wo;
  wo.max_planes = 16;
  wo.min_inliers = 100;
  const RoomPlanes planes = findRoomPlanes(cloud.points, wo);
  const RangeNoise noise = rangeNoiseOf(in);
  if (!s->free[M::kLeverZ]) {
    const FloorLever f = leverFromFloor(cloud, planes, noise);
    s->floor_z = f.ok;
    if (f.ok) {
      s->r.x(M::kLeverZ) += f.dz;
      s->floor_z_sigma = f.sigma;
    }
  }
  if (last) s->room = roomMeasures(cloud, planes, noise, in.room_truth_m, &s->room_warnings);
}

// Step 1: the wheels' ratios to the track and the gyro bias; w becomes (k_L T0, k_R T0, T0).
void wheelsAgainstGyro(const MobileRigCalibrationInput& in, Solution* s) {
  s->w = in.wheels;
  if (in.wheel_readings.empty() || in.gyro_readings.empty()) {
    s->wg.reason = "the log has no encoder or gyro readings";
    return;
  }
  s->wg = calibrateWheelsAgainstGyro(in.wheel_readings, in.gyro_readings, in.wheel_gyro);
  if (!s->wg.ok) return;
  const double T0 = in.wheels.wheel_distance_m;
  s->wheels = true;
  s->w.radius_left_m = s->wg.x(0) * T0;
  s->w.radius_right_m = s->wg.x(1) * T0;
}

}  // namespace

RigCalibration calibrateMobileRig(const MobileRigCalibrationInput& in) {
  Solution s;
  wheelsAgainstGyro(in, &s);
  const std::vector<OverlapRay> rays =
      overlapRays(in.scans, in.nominal.nominal_rpy_rad, in.options);
  s.x = Eigen::VectorXd::Zero(kParameters);
  s.x(M::kGamma) = in.nominal.gamma_rad;
  s.x(M::kBeta) = in.nominal.beta_rad;
  s.x(M::kAlpha) = in.nominal.alpha_rad;
  s.free.assign(size_t(kParameters), true);
  s.free[M::kDriftX] = s.free[M::kDriftY] = false;  // the wheels explain the track's drift
  s.free[kScale] = s.wheels;  // the scale alone would bend the radii's ratio as it is
  Sensitivities sens;
  constexpr int kPasses = 2;
  for (int pass = 0; pass < kPasses; ++pass) {
    if (in.progress) in.progress(double(pass) / kPasses);
    runOdometry(in, s.w, &sens);
    M model(rays, sens.base.track, in.nominal.t_BL_m, {{&sens.moved, sens.step}});
    std::vector<bool> try_free = s.free;
    // The second pass's odometry differs from the first's only by the wheels' common scale (some
    // tenths of a percent), which leaves what the drive observes as it was: it solves over the
    // first pass's choice at once, without the angles-only solve that made it (10 s of 83 on the
    // 480 s plan drive, seed 3; the angles moved by 0.001 mrad).
    s.r = pass == 0 ? solveObservable(rays, model, s.x, in, &try_free)
                    : solve(rays, model, s.x, try_free, in);
    if (!s.r.ok) {
      RigCalibration failed;
      failed.warnings.push_back("nothing calibrated: " + s.r.reason);
      return failed;
    }
    if (pass == 0) s.rms_before = s.r.residual_before_m;
    if (pass + 1 == kPasses) s.not_widened = widenByPointToPlane(rays, model, in, try_free, &s.r);
    s.free = try_free;
    floorAndRoom(in, rays, model, pass + 1 == kPasses, &s);
    s.x = s.r.x;
    s.w = scaled(s.w, 1.0 + s.x(kScale));
    s.x(kScale) = 0.0;  // now in w
  }
  if (!s.wheels) s.wg.x(2) = 0.0;
  if (in.progress) in.progress(1.0);
  return report(in, s);
}

}  // namespace sweepmap
