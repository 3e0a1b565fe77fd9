#include "sim/profiler.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/angles.hpp"
#include "sim/artefacts.hpp"

namespace sweepmap {

namespace {

// Neighbouring columns are at a depth edge (mixed pixels: the line's spot, some 0.1 mm wide,
// falls on both surfaces) where either's hit lies farther than this from the other's tangent
// plane: a step, or two surfaces. A steep wall seen at glancing incidence is no edge, though
// its columns' ranges differ by millimetres.
constexpr double kEdgeStepMm = 0.5;

// Distance along the ray to the plane w . p = h (w unit), if ahead.
std::optional<double> toPlane(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                              const Eigen::Vector3d& w, double h) {
  const double den = w.dot(d);
  if (std::fabs(den) < 1e-12) return std::nullopt;
  const double t = (h - w.dot(o)) / den;
  if (t <= 0) return std::nullopt;
  return t;
}

}  // namespace

void ProfilerConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "column_count", &column_count, "", "points per full profile (camera columns)");
  s.add(p + "near_mm", &near_mm, "mm", "nearest measurable distance below the sensor's origin");
  s.add(p + "far_mm", &far_mm, "mm", "farthest measurable distance below the sensor's origin");
  s.add(p + "fov_far_mm", &fov_far_mm, "mm", "length of the laser line at far_mm");
  s.add(p + "profile_rate_hz", &profile_rate_hz, "Hz", "profiles per second");
  s.add(p + "device", &device, "", "the profile sensor to open: sim (no real driver yet)");
}

double ProfilerConfig::fanHalfAngleRad() const { return std::atan(fov_far_mm / 2.0 / far_mm); }

void TurntableReference::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "declared", &declared, "",
        "the base carries a flat reference face (a fence or stop) whose normal's azimuth is known "
        "by construction; it defines X_r and so the encoder zero (false: no such face, the zero "
        "is not observable)");
  s.add(p + "normal_azimuth_deg", &normal_azimuth_deg, "deg",
        "the face normal's horizontal direction, from X_r counter-clockwise seen from above");
  s.add(p + "normal_tilt_deg", &normal_tilt_deg, "deg",
        "the face normal from vertical, nominal (recognises the face's sweep)");
  s.add(p + "azimuth_sigma_deg", &azimuth_sigma_deg, "deg",
        "how well construction fixes the azimuth (added to the encoder zero's sigma)");
}

void TurntableConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "counts_per_revolution", &counts_per_revolution, "", "encoder counts per turn");
  s.add(p + "speed_deg_s", &speed_deg_s, "deg/s", "turning speed during a sweep");
  s.add(p + "sweep_start_deg", &sweep_start_deg, "deg",
        "encoder angle (before its zero) where a sweep starts");
  s.add(p + "sweep_end_deg", &sweep_end_deg, "deg", "encoder angle where a sweep ends");
  s.add(p + "device", &device, "", "the turntable to open: sim (no real driver yet)");
  reference.declare(s, p + "reference.");
}

void TestPieceConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "distance_mm", &distance_mm, "mm", "top face below the sensor's origin");
  s.add(p + "block_length_mm", &block_length_mm, "mm", "block along the scanning direction");
  s.add(p + "block_width_mm", &block_width_mm, "mm", "block along the laser line");
  s.add(p + "spacing_mm", &spacing_mm, "mm", "centre to centre of neighbouring grooves");
  s.add(p + "left_diameter_mm", &left_diameter_mm, "mm", "first round groove's diameter");
  s.add(p + "left_depth_mm", &left_depth_mm, "mm", "first round groove's depth");
  s.add(p + "right_diameter_mm", &right_diameter_mm, "mm", "second round groove's diameter");
  s.add(p + "right_depth_mm", &right_depth_mm, "mm", "second round groove's depth");
  s.add(p + "rect_length_mm", &rect_length_mm, "mm", "rectangular groove along the scan");
  s.add(p + "rect_width_mm", &rect_width_mm, "mm", "rectangular groove along the laser line");
  s.add(p + "rect_depth_mm", &rect_depth_mm, "mm", "rectangular groove's depth");
}

void SimProfileConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "scene", &scene, "", "plate (plate_count poses, a sweep each) | test_piece");
  s.add(p + "offset_m_mm", &offset_m_mm, "mm", "true M (axis to laser plane)");
  s.add(p + "offset_n_mm", &offset_n_mm, "mm", "true N (foot of the perpendicular to origin)");
  s.add(p + "laser_tilt_deg", &laser_tilt_deg, "deg", "true tilt of the laser plane from the axis");
  s.add(p + "encoder_zero_deg", &encoder_zero_deg, "deg",
        "true turntable angle at encoder count 0");
  s.add(p + "encoder_noise_counts", &encoder_noise_counts, "counts",
        "encoder noise sigma (before quantisation)");
  s.add(p + "range_noise_sigma_mm", &range_noise_sigma_mm, "mm", "range noise sigma along a ray");
  s.add(p + "mixed_pixel_probability", &mixed_pixel_probability, "",
        "a column at a depth edge (0.5 mm to its neighbour) returns a range between the two");
  s.add(p + "dropout_glancing_probability", &dropout_glancing_probability, "",
        "no return at 90 deg incidence (0 up to 70 deg, linear between)");
  s.add(p + "dropout_spot_probability", &dropout_spot_probability, "",
        "no return from a column (a dark or specular spot of the surface)");
  s.add(p + "plate_count", &plate_count, "", "m: plate poses, one sweep each");
  s.add(p + "plate_size_mm", &plate_size_mm, "mm", "side of the square plate");
  s.add(p + "plate_distance_mm", &plate_distance_mm, "mm", "plate centre below the sensor");
  s.add(p + "plate_distance_step_mm", &plate_distance_step_mm, "mm",
        "pose k's centre is step * (k mod 3 - 1) farther");
  s.add(p + "plate_tilt_deg", &plate_tilt_deg, "deg", "plate normal from vertical");
  s.add(p + "plate_tilt_spread_deg", &plate_tilt_spread_deg, "deg",
        "the poses' tilt directions spread evenly over this angle (0: all plates parallel)");
  s.add(p + "pause_s", &pause_s, "s", "pause between sweeps (the plate is moved)");
  s.add(p + "reference_sweep", &reference_sweep, "",
        "the plate scene ends with a sweep over the base's reference face (turntable.reference)");
  s.add(p + "reference_azimuth_deg", &reference_azimuth_deg, "deg",
        "true azimuth of the reference face's normal (its construction error against "
        "turntable.reference.normal_azimuth_deg)");
  test_piece.declare(s, p + "test_piece.");
}

ProfileGeometry SimProfileConfig::trueGeometry() const {
  return {offset_m_mm, offset_n_mm, laser_tilt_deg * kDegToRad, encoder_zero_deg * kDegToRad};
}

std::vector<std::string> SimProfileConfig::artefactsOff() {
  return {"sim.mixed_pixel_probability=0", "sim.dropout_glancing_probability=0",
          "sim.dropout_spot_probability=0"};
}

void SimProfileConfig::switchArtefactsOff() {
  mixed_pixel_probability = dropout_glancing_probability = dropout_spot_probability = 0.0;
}

namespace {

// The encoder angle (before the zero) in the middle of a sweep.
double sweepMiddleRad(const TurntableConfig& t) {
  return 0.5 * (t.sweep_start_deg + t.sweep_end_deg) * kDegToRad;
}

}  // namespace

std::vector<PlatePose> platePoses(const SimProfileConfig& sim, const TurntableConfig& turntable) {
  const ProfileGeometry truth = sim.trueGeometry();
  const double mid = sweepMiddleRad(turntable);
  std::vector<PlatePose> poses;
  for (int k = 0; k < sim.plate_count; ++k) {
    const double distance = sim.plate_distance_mm + sim.plate_distance_step_mm * (k % 3 - 1);
    PlatePose p;
    // Centred under the laser line's middle at the sweep's middle.
    p.centre = profilePointInRigFrame(truth, 0.0, -distance, mid);
    const double dir = sim.plate_tilt_spread_deg * kDegToRad * k / sim.plate_count;
    const double tilt = sim.plate_tilt_deg * kDegToRad;
    // Tilt directions measured in the sensor's heading at the sweep's middle.
    const SensorPose s = sensorPoseInRigFrame(truth, mid);
    const Eigen::Vector3d x_s = s.y_axis.cross(s.z_axis).normalized();
    const Eigen::Vector3d horizontal = std::cos(dir) * x_s + std::sin(dir) * s.y_axis;
    p.normal =
        (std::cos(tilt) * Eigen::Vector3d::UnitZ() + std::sin(tilt) * horizontal).normalized();
    p.e1 = p.normal.cross(s.y_axis).normalized();
    p.e2 = p.normal.cross(p.e1);
    p.half_size_mm = sim.plate_size_mm / 2.0;
    poses.push_back(p);
  }
  if (sim.reference_sweep) poses.push_back(referencePose(sim, turntable));
  return poses;
}

PlatePose referencePose(const SimProfileConfig& sim, const TurntableConfig& turntable) {
  const ProfileGeometry truth = sim.trueGeometry();
  const double mid = sweepMiddleRad(turntable);
  PlatePose p;
  p.centre = profilePointInRigFrame(truth, 0.0, -sim.plate_distance_mm, mid);
  // In O_r itself, not in the sensor's heading: the face is fixed to the base.
  const double azimuth = sim.reference_azimuth_deg * kDegToRad;
  const double tilt = turntable.reference.normal_tilt_deg * kDegToRad;
  p.normal = Eigen::Vector3d(std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth),
                             std::cos(tilt));
  const SensorPose s = sensorPoseInRigFrame(truth, mid);
  p.e1 = p.normal.cross(s.y_axis).normalized();
  p.e2 = p.normal.cross(p.e1);
  p.half_size_mm = sim.plate_size_mm / 2.0;
  return p;
}

ProfileScene ProfileScene::plate(const PlatePose& pose) {
  ProfileScene s;
  s.plate_ = pose;
  return s;
}

ProfileScene ProfileScene::testPiece(const SimProfileConfig& sim,
                                     const TurntableConfig& turntable) {
  ProfileScene s;
  s.test_piece_ = true;
  s.piece_ = sim.test_piece;
  const ProfileGeometry truth = sim.trueGeometry();
  const SensorPose pose = sensorPoseInRigFrame(truth, sweepMiddleRad(turntable));
  s.w_ = Eigen::Vector3d::UnitZ();
  s.u_ = (pose.y_axis - pose.y_axis.dot(s.w_) * s.w_).normalized();
  s.v_ = s.w_.cross(s.u_);
  s.origin_ =
      profilePointInRigFrame(truth, 0.0, -sim.test_piece.distance_mm, sweepMiddleRad(turntable));
  return s;
}

std::optional<ProfileScene::Frame> ProfileScene::testPieceFrame() const {
  if (!test_piece_) return std::nullopt;
  return Frame{origin_, u_, v_, w_};
}

std::optional<ProfileScene::Hit> ProfileScene::cast(const Eigen::Vector3d& origin,
                                                    const Eigen::Vector3d& dir) const {
  if (test_piece_) return castTestPiece(origin, dir);
  if (!plate_) return std::nullopt;
  const PlatePose& p = *plate_;
  const auto t = toPlane(origin, dir, p.normal, p.distance());
  if (!t) return std::nullopt;
  const Eigen::Vector3d q = origin + *t * dir - p.centre;
  if (std::fabs(q.dot(p.e1)) > p.half_size_mm || std::fabs(q.dot(p.e2)) > p.half_size_mm) {
    return std::nullopt;
  }
  return Hit{*t, p.normal};
}

std::optional<ProfileScene::Hit> ProfileScene::castTestPiece(const Eigen::Vector3d& o_r,
                                                             const Eigen::Vector3d& d_r) const {
  // In the piece's frame: top face w = 0, the block below it; grooves cut into it.
  const Eigen::Vector3d o((o_r - origin_).dot(u_), (o_r - origin_).dot(v_),
                          (o_r - origin_).dot(w_));
  const Eigen::Vector3d d(d_r.dot(u_), d_r.dot(v_), d_r.dot(w_));
  const TestPieceConfig& c = piece_;
  struct Round {
    double v, r, depth;
  };
  const Round rounds[] = {{-c.spacing_mm, c.left_diameter_mm / 2, c.left_depth_mm},
                          {c.spacing_mm, c.right_diameter_mm / 2, c.right_depth_mm}};
  const auto inRound = [&](const Round& g, const Eigen::Vector3d& p) {
    return p.x() * p.x() + (p.y() - g.v) * (p.y() - g.v) <= g.r * g.r;
  };
  const auto inRect = [&](const Eigen::Vector3d& p) {
    return std::fabs(p.x()) <= c.rect_width_mm / 2 && std::fabs(p.y()) <= c.rect_length_mm / 2;
  };
  const auto onBlock = [&](const Eigen::Vector3d& p) {
    return std::fabs(p.x()) <= c.block_width_mm / 2 && std::fabs(p.y()) <= c.block_length_mm / 2;
  };
  const auto at = [&](double t) { return Eigen::Vector3d(o + t * d); };
  std::optional<Hit> best;
  // The nearer of `best` and a hit at `t` of a surface whose normal is `n` (piece frame).
  const auto take = [&](double t, const Eigen::Vector3d& n) {
    if (!best || t < best->range_mm) best = Hit{t, (n.x() * u_ + n.y() * v_ + n.z() * w_)};
  };
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  // Top face, outside the grooves.
  if (const auto t = toPlane(o, d, up, 0.0)) {
    const Eigen::Vector3d p = at(*t);
    if (onBlock(p) && !inRect(p) && !inRound(rounds[0], p) && !inRound(rounds[1], p)) {
      take(*t, up);
    }
  }
  // Groove bottoms and walls.
  for (const Round& g : rounds) {
    if (const auto t = toPlane(o, d, up, -g.depth); t && inRound(g, at(*t))) take(*t, up);
    // Inner cylinder wall: |(p - axis)_uv| = r, -depth <= w <= 0.
    const double a = d.x() * d.x() + d.y() * d.y();
    const double b = 2 * (o.x() * d.x() + (o.y() - g.v) * d.y());
    const double k = o.x() * o.x() + (o.y() - g.v) * (o.y() - g.v) - g.r * g.r;
    const double disc = b * b - 4 * a * k;
    if (a > 1e-12 && disc >= 0) {
      for (const double t : {(-b - std::sqrt(disc)) / (2 * a), (-b + std::sqrt(disc)) / (2 * a)}) {
        const Eigen::Vector3d p = at(t);
        if (t > 0 && p.z() <= 0 && p.z() >= -g.depth) {
          take(t, Eigen::Vector3d(p.x(), p.y() - g.v, 0.0) / g.r);  // radial
        }
      }
    }
  }
  if (const auto t = toPlane(o, d, up, -c.rect_depth_mm); t && inRect(at(*t))) take(*t, up);
  // Rectangular groove's walls: the planes u = +-width/2 and v = +-length/2 inside its box.
  const auto inRectBox = [&](const Eigen::Vector3d& p) {
    return std::fabs(p.x()) <= c.rect_width_mm / 2 + 1e-9 &&
           std::fabs(p.y()) <= c.rect_length_mm / 2 + 1e-9 && p.z() <= 0 &&
           p.z() >= -c.rect_depth_mm;
  };
  for (int axis = 0; axis < 2; ++axis) {
    const double half = (axis == 0 ? c.rect_width_mm : c.rect_length_mm) / 2;
    for (const double side : {-half, half}) {
      const Eigen::Vector3d n = axis == 0 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
      if (const auto t = toPlane(o, d, n, side); t && inRectBox(at(*t))) take(*t, n);
    }
  }
  return best;
}

SimProfiler::SimProfiler(const ProfilerConfig& profiler, const TurntableConfig& turntable,
                         const SimProfileConfig& sim, uint64_t seed)
    : profiler_(profiler),
      turntable_(turntable),
      sim_(sim),
      truth_(sim.trueGeometry()),
      range_rng_(seed * 2 + 1),
      encoder_rng_(seed * 2 + 2),
      artefact_rng_(seed ^ 0x6a09e667f3bcc909ULL) {}

int64_t SimProfiler::sweepDurationUs() const {
  const double span = std::fabs(turntable_.sweep_end_deg - turntable_.sweep_start_deg);
  return static_cast<int64_t>(std::llround(span / turntable_.speed_deg_s * 1e6));
}

std::vector<Profile> SimProfiler::sweep(const ProfileScene& scene, int32_t sweep_id,
                                        int64_t start_utime) {
  const double span_deg = turntable_.sweep_end_deg - turntable_.sweep_start_deg;
  const double duration_s = std::fabs(span_deg) / turntable_.speed_deg_s;
  const int64_t count = static_cast<int64_t>(std::floor(duration_s * profiler_.profile_rate_hz));
  std::vector<Profile> profiles;
  profiles.reserve(static_cast<size_t>(count) + 1);
  for (int64_t j = 0; j <= count; ++j) {
    const double t_s = j / profiler_.profile_rate_hz;
    // The encoder angle (before the zero): constant speed from the sweep's start.
    const double encoder_deg = turntable_.sweep_start_deg + span_deg * t_s / duration_s;
    profiles.push_back(profile(scene, encoder_deg * kDegToRad,
                               start_utime + static_cast<int64_t>(std::llround(t_s * 1e6)),
                               sweep_id));
  }
  return profiles;
}

Profile SimProfiler::profile(const ProfileScene& scene, double encoder_rad, int64_t utime,
                             int32_t sweep_id) {
  Profile p;
  p.utime = utime;
  p.sequence = sequence_++;
  p.sweep_id = sweep_id;
  p.counts_per_revolution = turntable_.counts_per_revolution;
  p.column_count = profiler_.column_count;
  const double counts_exact = encoder_rad / (2 * M_PI) * turntable_.counts_per_revolution;
  p.encoder_counts = static_cast<int64_t>(
      std::llround(counts_exact + sim_.encoder_noise_counts * normal_(encoder_rng_)));
  const SensorPose pose = sensorPoseInRigFrame(truth_, encoder_rad);
  const double half_fan = profiler_.fanHalfAngleRad();
  const auto phiOf = [&](int i) {
    return profiler_.column_count > 1 ? -half_fan + 2 * half_fan * i / (profiler_.column_count - 1)
                                      : 0.0;
  };
  // The true range of each column's return (0: none), then the mixed pixels, then the noise.
  const size_t columns = static_cast<size_t>(std::max(0, profiler_.column_count));
  std::vector<double> ranges(columns, 0.0), noise(columns);
  std::vector<Eigen::Vector3d> points(columns), normals(columns);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (size_t i = 0; i < columns; ++i) {
    const double phi = phiOf(static_cast<int>(i));
    // The ray in the sensor frame: (0, sin phi, -cos phi), downwards.
    const Eigen::Vector3d dir =
        (std::sin(phi) * pose.y_axis - std::cos(phi) * pose.z_axis).normalized();
    noise[i] = sim_.range_noise_sigma_mm * normal_(range_rng_);  // one per column
    const auto hit = scene.cast(pose.origin, dir);
    if (!hit) continue;
    const double incidence_deg =
        std::acos(std::min(1.0, std::fabs(hit->normal.dot(dir)))) / kDegToRad;
    if (glancingDropout(incidence_deg, sim_.dropout_glancing_probability, artefact_rng_)) continue;
    if (sim_.dropout_spot_probability > 0 &&
        uniform(artefact_rng_) < sim_.dropout_spot_probability) {
      continue;
    }
    ranges[i] = hit->range_mm;
    points[i] = pose.origin + hit->range_mm * dir;
    normals[i] = hit->normal;
  }
  const auto step = [&](const std::vector<double>&, size_t i, size_t j) {
    const Eigen::Vector3d d = points[j] - points[i];
    return std::max(std::fabs(normals[i].dot(d)), std::fabs(normals[j].dot(d))) > kEdgeStepMm;
  };
  mixEdges(&ranges, step, sim_.mixed_pixel_probability, artefact_rng_);
  for (size_t i = 0; i < columns; ++i) {
    if (ranges[i] == 0.0) continue;
    const double phi = phiOf(static_cast<int>(i));
    const double r = ranges[i] + noise[i];
    const double y = r * std::sin(phi), z = -r * std::cos(phi);
    if (-z < profiler_.near_mm || -z > profiler_.far_mm) continue;
    p.column.push_back(static_cast<int16_t>(i));
    p.y_mm.push_back(static_cast<float>(y));
    p.z_mm.push_back(static_cast<float>(z));
  }
  return p;
}

}  // namespace sweepmap
