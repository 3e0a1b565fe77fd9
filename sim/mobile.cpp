#include "sim/mobile.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>

#include "core/angles.hpp"

namespace sweepmap {
namespace {

// The simulation's random streams, one generator each seeded `seed * 8 + stream`, so that no
// stream's draws depend on how many another made.
enum class Stream : uint64_t { kWheels = 1, kImu = 2, kLidar = 3, kSlip = 4, kArtefacts = 5 };
uint64_t streamSeed(uint64_t seed, Stream s) { return seed * 8 + static_cast<uint64_t>(s); }

constexpr double kGravity = 9.80665;

Eigen::Isometry3d planar(const Pose2& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(p.theta_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.x_m, p.y_m, 0.0);
  return T;
}

// Throws unless the path's first `length` metres stay inside the room (half sizes hl, hw).
void requireInside(const MobilePath& path, double length, double hl, double hw,
                   const std::string& what) {
  for (double s = 0.0; s <= length; s += 0.05) {
    const Pose2 p = path.poseAt(s);
    if (std::abs(p.x_m) >= hl || std::abs(p.y_m) >= hw) {
      throw ConfigError("sim: " + what + " leaves the room at arc length " + std::to_string(s) +
                        " m");
    }
  }
}

}  // namespace

void SimMobileConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "path", &path, "",
        "driven path: circle (Miao 2022's calibration drive), loop (rounded rectangle), figure8 "
        "(turns both ways and straights: calib rig's drive) or file (path_file)");
  s.add(
      p + "path_file", &path_file, "",
      "path: file — YAML of start pose and segments in the room frame (relative to the rig file)");
  s.add(p + "circle_radius_m", &circle_radius_m, "m", "circle path radius (Miao 2022: 0.83)");
  s.add(p + "circle_center_x_m", &circle_center_x_m, "m", "circle centre X in the room");
  s.add(p + "circle_center_y_m", &circle_center_y_m, "m", "circle centre Y in the room");
  s.add(p + "loop_wall_clearance_m", &loop_wall_clearance_m, "m",
        "loop path: distance of the rounded rectangle from the walls");
  s.add(p + "loop_corner_radius_m", &loop_corner_radius_m, "m", "loop path: corner radius");
  s.add(p + "figure8_radius_m", &figure8_radius_m, "m", "figure8 path: radius of each lobe");
  s.add(p + "figure8_lobe_spacing_m", &figure8_lobe_spacing_m, "m",
        "figure8 path: distance between the lobes' centres (along the room's X)");
  s.add(p + "figure8_center_x_m", &figure8_center_x_m, "m",
        "figure8 path: X of the crossing in the room");
  s.add(p + "figure8_center_y_m", &figure8_center_y_m, "m",
        "figure8 path: Y of the crossing in the room");
  s.add(p + "speed_m_s", &speed_m_s, "m/s", "cruise speed");
  s.add(p + "accel_m_s2", &accel_m_s2, "m/s^2", "ramp acceleration at start and stop");
  s.add(p + "duration_s", &duration_s, "s", "length of the run (the car stops at its end)");
  s.add(p + "stop_interval_s", &stop_interval_s, "s",
        "> 0: the car stops after each leg of driving this long (ramps included); 0: no stops");
  s.add(p + "stop_duration_s", &stop_duration_s, "s", "rest at each stop");
  s.add(p + "wheel_ticks_rate_hz", &wheel_ticks_rate_hz, "Hz", "encoder reading rate");
  s.add(p + "encoder_speed_sigma_fraction", &encoder_speed_sigma_fraction, "",
        "white wheel speed error per reading, fraction of the speed");
  s.add(p + "slip_mean_interval_s", &slip_mean_interval_s, "s",
        "mean time between wheel slip events (exponential; <= 0: none)");
  s.add(p + "slip_min_duration_s", &slip_min_duration_s, "s", "shortest slip event");
  s.add(p + "slip_max_duration_s", &slip_max_duration_s, "s", "longest slip event");
  s.add(p + "slip_min_fraction", &slip_min_fraction, "",
        "least excess turning of the slipping wheel (fraction of its ground speed)");
  s.add(p + "slip_max_fraction", &slip_max_fraction, "",
        "most excess turning of the slipping wheel");
  s.add(p + "imu_rate_hz", &imu_rate_hz, "Hz", "IMU sample rate");
  s.add(p + "gyro_sigma_rad_s", &gyro_sigma_rad_s, "rad/s", "gyro white noise, each axis");
  s.add(p + "gyro_bias_z_rad_s", &gyro_bias_z_rad_s, "rad/s",
        "constant z gyro bias (x, y unbiased)");
  s.add(p + "accel_sigma_m_s2", &accel_sigma_m_s2, "m/s^2", "accelerometer white noise");
  s.add(p + "roll_error_deg", &roll_error_deg, "deg", "static roll error of the IMU attitude");
  s.add(p + "pitch_error_deg", &pitch_error_deg, "deg", "static pitch error of the IMU attitude");
  s.add(p + "yaw_error_deg", &yaw_error_deg, "deg", "static yaw error of the IMU attitude");
  s.add(p + "attitude_sigma_deg", &attitude_sigma_deg, "deg", "white noise of the IMU attitude");
  s.add(p + "scan_rate_hz", &scan_rate_hz, "Hz", "lidar turns per second (X4: 7)");
  s.add(p + "sample_rate_hz", &sample_rate_hz, "Hz", "lidar rays per second (X4: 5000)");
  s.add(p + "range_min_m", &range_min_m, "m", "shortest valid range (X4: 0.12)");
  s.add(p + "range_max_m", &range_max_m, "m", "longest valid range (X4: 10)");
  s.add(p + "range_sigma_fraction", &range_sigma_fraction, "",
        "range noise sigma, fraction of the range");
  s.add(p + "lidar_latency_ms", &lidar_latency_ms, "ms",
        "scan delivered this long after its last ray");
  s.add(p + "wheel_radius_left_error_fraction", &wheel_radius_left_error_fraction, "",
        "true left wheel radius = odometry.wheel_radius_m (1 + this)");
  s.add(p + "wheel_radius_right_error_fraction", &wheel_radius_right_error_fraction, "",
        "true right wheel radius = odometry.wheel_radius_right_m (or wheel_radius_m when that "
        "is 0) (1 + this)");
  s.add(p + "wheel_distance_error_m", &wheel_distance_error_m, "m",
        "true track width = odometry.wheel_distance_m + this");
  s.add(p + "lever_error_x_m", &lever_error_x_m, "m", "true lidar centre = mounting.x_m + this");
  s.add(p + "lever_error_y_m", &lever_error_y_m, "m", "true lidar centre = mounting.y_m + this");
  s.add(p + "lever_error_z_m", &lever_error_z_m, "m", "true lidar centre = mounting.z_m + this");
  s.add(p + "lidar_time_offset_ms", &lidar_time_offset_ms, "ms",
        "the lidar's stamps run this far ahead of the odometry's clock");
  s.add(p + "gamma_true_rad", &gamma_true_rad, "rad", "true mounting error about body x");
  s.add(p + "beta_true_rad", &beta_true_rad, "rad", "true mounting error about body y");
  s.add(p + "alpha_true_rad", &alpha_true_rad, "rad", "true mounting error about body z");
  s.add(p + "truth_rate_hz", &truth_rate_hz, "Hz", "TRUTH_POSE rate");
  declareArtefacts(s, p);
}

void SimMobileConfig::validate(const std::string& source) const {
  const auto require = [&](bool ok, const std::string& key, const std::string& why) {
    if (!ok) throw ConfigError(source + ": key 'sim." + key + "' " + why);
  };
  require(path == "circle" || path == "loop" || path == "figure8" || path == "file", "path",
          "must be circle, loop, figure8 or file");
  require(figure8_radius_m > 0, "figure8_radius_m", "must be positive");
  require(figure8_lobe_spacing_m > 2 * figure8_radius_m, "figure8_lobe_spacing_m",
          "must exceed twice sim.figure8_radius_m (the lobes may not overlap)");
  require(stop_interval_s >= 0, "stop_interval_s", "must be >= 0");
  require(stop_interval_s == 0 || stop_duration_s > 0, "stop_duration_s",
          "must be positive when sim.stop_interval_s is");
  require(path != "file" || !path_file.empty(), "path_file",
          "must name a file when sim.path is file");
  require(circle_radius_m > 0, "circle_radius_m", "must be positive");
  require(loop_wall_clearance_m > 0, "loop_wall_clearance_m", "must be positive");
  require(loop_corner_radius_m > 0, "loop_corner_radius_m", "must be positive");
  require(speed_m_s > 0 && speed_m_s < 5, "speed_m_s", "must be in (0, 5)");
  require(accel_m_s2 > 0, "accel_m_s2", "must be positive");
  require(duration_s > 0 && duration_s <= 36000, "duration_s", "must be in (0, 36000]");
  require(wheel_ticks_rate_hz > 0 && wheel_ticks_rate_hz <= 10000, "wheel_ticks_rate_hz",
          "must be in (0, 10000]");
  require(encoder_speed_sigma_fraction >= 0, "encoder_speed_sigma_fraction", "must be >= 0");
  require(slip_min_duration_s > 0 && slip_min_duration_s <= slip_max_duration_s,
          "slip_min_duration_s", "must be positive and <= slip_max_duration_s");
  require(slip_min_fraction >= 0 && slip_min_fraction <= slip_max_fraction, "slip_min_fraction",
          "must be >= 0 and <= slip_max_fraction");
  require(imu_rate_hz > 0 && imu_rate_hz <= 10000, "imu_rate_hz", "must be in (0, 10000]");
  require(gyro_sigma_rad_s >= 0, "gyro_sigma_rad_s", "must be >= 0");
  require(accel_sigma_m_s2 >= 0, "accel_sigma_m_s2", "must be >= 0");
  require(attitude_sigma_deg >= 0, "attitude_sigma_deg", "must be >= 0");
  require(scan_rate_hz > 0 && scan_rate_hz <= 100, "scan_rate_hz", "must be in (0, 100]");
  require(sample_rate_hz >= 10 * scan_rate_hz && sample_rate_hz <= 1e6, "sample_rate_hz",
          "must give at least 10 rays per scan and at most 1e6 rays/s");
  require(range_min_m > 0 && range_min_m < range_max_m, "range_min_m",
          "must be in (0, range_max_m)");
  require(range_sigma_fraction >= 0 && range_sigma_fraction < 0.5, "range_sigma_fraction",
          "must be in [0, 0.5)");
  require(lidar_latency_ms >= 0, "lidar_latency_ms", "must be >= 0");
  require(std::abs(wheel_radius_left_error_fraction) < 0.2, "wheel_radius_left_error_fraction",
          "must be within +-0.2");
  require(std::abs(wheel_radius_right_error_fraction) < 0.2, "wheel_radius_right_error_fraction",
          "must be within +-0.2");
  require(std::abs(wheel_distance_error_m) < 0.1, "wheel_distance_error_m", "must be within +-0.1");
  require(std::abs(lidar_time_offset_ms) <= 1000, "lidar_time_offset_ms", "must be within +-1000");
  require(truth_rate_hz > 0 && truth_rate_hz <= 10000, "truth_rate_hz", "must be in (0, 10000]");
}

// ---------------------------------------------------------------- path

MobilePath::MobilePath(std::vector<Segment> segments) : segments_(std::move(segments)) {
  for (const Segment& s : segments_) {
    starts_.push_back(length_);
    length_ += s.length;
    turn_per_lap_ += s.curvature * s.length;
  }
}

MobilePath MobilePath::circle(double cx, double cy, double r) {
  return MobilePath({{cx, cy - r, 0.0, 2.0 * M_PI * r, 1.0 / r}});
}

MobilePath MobilePath::roundedRectangle(double x0, double x1, double y0, double y1, double rc) {
  const double lx = x1 - x0 - 2 * rc, ly = y1 - y0 - 2 * rc, arc = 0.5 * M_PI * rc;
  return MobilePath({{x0 + rc, y0, 0.0, lx, 0.0},
                     {x1 - rc, y0, 0.0, arc, 1.0 / rc},
                     {x1, y0 + rc, 0.5 * M_PI, ly, 0.0},
                     {x1, y1 - rc, 0.5 * M_PI, arc, 1.0 / rc},
                     {x1 - rc, y1, M_PI, lx, 0.0},
                     {x0 + rc, y1, M_PI, arc, 1.0 / rc},
                     {x0, y1 - rc, 1.5 * M_PI, ly, 0.0},
                     {x0, y0 + rc, 1.5 * M_PI, arc, 1.0 / rc}});
}

MobilePath MobilePath::fromFile(const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    throw ConfigError("path file " + file + ": " + e.what());
  }
  const auto number = [&](const YAML::Node& n, const char* key, const std::string& where) {
    if (!n[key]) throw ConfigError("path file " + file + ": " + where + " has no '" + key + "'");
    double v = 0.0;
    try {
      v = n[key].as<double>();
    } catch (const YAML::Exception&) {
      throw ConfigError("path file " + file + ": " + where + " '" + key + "' is not a number");
    }
    if (!std::isfinite(v))
      throw ConfigError("path file " + file + ": " + where + " '" + key + "' is not finite");
    return v;
  };
  if (!root.IsMap() || !root["start"] || !root["segments"] || !root["segments"].IsSequence() ||
      root["segments"].size() == 0) {
    throw ConfigError("path file " + file + ": needs 'start' and a non-empty list 'segments'");
  }
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (key != "start" && key != "segments")
      throw ConfigError("path file " + file + ": unknown key '" + key + "'");
  }
  const double x = number(root["start"], "x_m", "start");
  const double y = number(root["start"], "y_m", "start");
  const double theta = number(root["start"], "heading_deg", "start") * kDegToRad;
  std::vector<std::pair<double, double>> pieces;
  for (size_t i = 0; i < root["segments"].size(); ++i) {
    const YAML::Node n = root["segments"][i];
    const std::string where = "segment " + std::to_string(i);
    const double length = number(n, "length_m", where);
    if (!(length > 0))
      throw ConfigError("path file " + file + ": " + where + " 'length_m' must be > 0");
    double curvature = 0.0;
    if (n["radius_m"]) {
      const double r = number(n, "radius_m", where);
      if (std::abs(r) < 0.05)
        throw ConfigError("path file " + file + ": " + where + " '|radius_m|' must be >= 0.05");
      curvature = 1.0 / r;
    }
    pieces.emplace_back(length, curvature);
  }
  return chained(x, y, theta, pieces);
}

MobilePath MobilePath::chained(double x, double y, double theta,
                               const std::vector<std::pair<double, double>>& length_curvature) {
  std::vector<Segment> segments;
  for (const auto& [length, curvature] : length_curvature) {
    segments.push_back({x, y, theta, length, curvature});
    const MobilePath one({segments.back()});
    const Pose2 end = one.poseAt(length * (1.0 - 1e-12));
    x = end.x_m;
    y = end.y_m;
    theta = theta + curvature * length;
  }
  return MobilePath(std::move(segments));
}

MobilePath MobilePath::figureEight(double cx, double cy, double r, double spacing) {
  // The straights are the lobes' inner tangents: they cross at the centre at +-phi to X,
  // sin(phi) = r / (spacing / 2), and each lobe's arc turns pi + 2 phi.
  const double d = 0.5 * spacing, phi = std::asin(r / d);
  const double straight = 2.0 * std::sqrt(d * d - r * r), arc = r * (M_PI + 2.0 * phi);
  return chained(cx, cy, phi,
                 {{0.5 * straight, 0.0},
                  {arc, -1.0 / r},
                  {straight, 0.0},
                  {arc, 1.0 / r},
                  {0.5 * straight, 0.0}});
}

bool MobilePath::closed() const {
  const Segment& first = segments_.front();
  const Pose2 end = poseAt(length_ * (1.0 - 1e-12));
  return std::hypot(end.x_m - first.x0, end.y_m - first.y0) < 0.01 &&
         std::abs(wrapAngle(end.theta_rad - first.theta0)) < 0.01;
}

const MobilePath::Segment& MobilePath::find(double s, double* local, int* lap) const {
  const double laps = std::floor(s / length_);
  *lap = static_cast<int>(laps);
  double r = s - laps * length_;
  size_t i =
      static_cast<size_t>(std::upper_bound(starts_.begin(), starts_.end(), r) - starts_.begin());
  i = i == 0 ? 0 : i - 1;
  *local = std::min(r - starts_[i], segments_[i].length);
  return segments_[i];
}

Pose2 MobilePath::poseAt(double s) const {
  double l;
  int lap;
  const Segment& g = find(s, &l, &lap);
  Pose2 p;
  const double th = g.theta0 + g.curvature * l;
  if (g.curvature == 0.0) {
    p.x_m = g.x0 + l * std::cos(g.theta0);
    p.y_m = g.y0 + l * std::sin(g.theta0);
  } else {
    p.x_m = g.x0 + (std::sin(th) - std::sin(g.theta0)) / g.curvature;
    p.y_m = g.y0 - (std::cos(th) - std::cos(g.theta0)) / g.curvature;
  }
  p.theta_rad = th + lap * turn_per_lap_;
  return p;
}

double MobilePath::curvatureAt(double s) const {
  double l;
  int lap;
  return find(s, &l, &lap).curvature;
}

// ---------------------------------------------------------------- car

SimMobile::SimMobile(const SimMobileConfig& config, const WheelGeometry& wheels,
                     const Eigen::Vector3d& nominal_rpy_rad, const Eigen::Vector3d& t_BL_m,
                     const Scene& scene, uint64_t seed, int64_t start_utime)
    : c_(config),
      wheels_(wheels),
      scene_(&scene),
      path_({{0, 0, 0, 1, 0}}),
      seed_(seed),
      start_utime_(start_utime),
      artefacts_(config, scene, streamSeed(seed, Stream::kArtefacts)) {
  c_.validate("sim");
  if (!(wheels.radius_m > 0) || !(wheels.ticks_per_revolution > 0) ||
      !(wheels.wheel_distance_m > 0)) {
    throw ConfigError("sim: wheel radius, ticks per revolution and wheel distance must be > 0");
  }
  const SceneConfig& sc = scene.config();
  const double hl = sc.room_length_m / 2, hw = sc.room_width_m / 2;
  if (c_.path == "circle") {
    const double r = c_.circle_radius_m;
    if (std::abs(c_.circle_center_x_m) + r >= hl || std::abs(c_.circle_center_y_m) + r >= hw) {
      throw ConfigError("sim: key 'sim.circle_center_x_m' puts the circle outside the room");
    }
    path_ = MobilePath::circle(c_.circle_center_x_m, c_.circle_center_y_m, r);
    s0_ = 0.0;
  } else if (c_.path == "file") {
    path_ = MobilePath::fromFile(c_.path_file);
    s0_ = 0.0;
    const double driven = distanceAt(c_.duration_s);
    if (!path_.closed() && driven > path_.length()) {
      throw ConfigError("sim: path file " + c_.path_file + " is open and " +
                        std::to_string(path_.length()) + " m long, but the drive covers " +
                        std::to_string(driven) + " m");
    }
    requireInside(path_, std::min(driven, path_.length()), hl, hw, "path file " + c_.path_file);
  } else if (c_.path == "figure8") {
    path_ = MobilePath::figureEight(c_.figure8_center_x_m, c_.figure8_center_y_m,
                                    c_.figure8_radius_m, c_.figure8_lobe_spacing_m);
    s0_ = 0.0;
    requireInside(path_, path_.length(), hl, hw, "key 'sim.figure8_center_x_m': the figure8");
  } else {
    const double m = c_.loop_wall_clearance_m, rc = c_.loop_corner_radius_m;
    if (2 * (m + rc) >= std::min(sc.room_length_m, sc.room_width_m)) {
      throw ConfigError("sim: key 'sim.loop_wall_clearance_m' leaves no loop inside the room");
    }
    path_ = MobilePath::roundedRectangle(-hl + m, hl - m, -hw + m, hw - m, rc);
    s0_ = 0.5 * (sc.room_length_m - 2 * m - 2 * rc);  // middle of the -Y straight
  }
  start_room_ = path_.poseAt(s0_);
  T_BL_ = Eigen::Isometry3d::Identity();
  T_BL_.linear() = rotationXYZ(c_.gamma_true_rad, c_.beta_true_rad, c_.alpha_true_rad) *
                   rotationXYZ(nominal_rpy_rad.x(), nominal_rpy_rad.y(), nominal_rpy_rad.z());
  T_BL_.translation() =
      t_BL_m + Eigen::Vector3d(c_.lever_error_x_m, c_.lever_error_y_m, c_.lever_error_z_m);
  rays_ = static_cast<int>(std::lround(c_.sample_rate_hz / c_.scan_rate_hz));

  // Slip schedule: exponential gaps after each event's end.
  if (c_.slip_mean_interval_s > 0) {
    std::mt19937_64 rng(streamSeed(seed, Stream::kSlip));
    std::exponential_distribution<double> gap(1.0 / c_.slip_mean_interval_s);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double t = 0.0;
    for (;;) {
      t += gap(rng);
      if (t >= c_.duration_s) break;
      SlipEvent e;
      e.start_s = t;
      e.end_s =
          t + c_.slip_min_duration_s + u(rng) * (c_.slip_max_duration_s - c_.slip_min_duration_s);
      e.right = u(rng) < 0.5;
      e.fraction = c_.slip_min_fraction + u(rng) * (c_.slip_max_fraction - c_.slip_min_fraction);
      slips_.push_back(e);
      t = e.end_s;
    }
  }
}

// The leg of driving that time t falls in: its start and its length (ramps included). Without
// stops the whole run is one leg.
void SimMobile::legAt(double t, double* start, double* length, int64_t* index) const {
  const double T = c_.duration_s;
  if (c_.stop_interval_s <= 0) {
    *start = 0.0;
    *length = T;
    *index = 0;
    return;
  }
  const double period = c_.stop_interval_s + c_.stop_duration_s;
  *index = static_cast<int64_t>(std::floor(std::clamp(t, 0.0, T) / period));
  *start = static_cast<double>(*index) * period;
  *length = std::max(0.0, std::min(c_.stop_interval_s, T - *start));
}

// Speed, distance and acceleration u into a leg of duration D that ramps up to the cruise
// speed and down to rest at its end.
double SimMobile::legSpeed(double u, double D) const {
  const double ta = std::min(c_.speed_m_s / c_.accel_m_s2, D / 2);
  if (u <= 0 || u >= D) return 0.0;
  if (u < ta) return c_.accel_m_s2 * u;
  if (u > D - ta) return c_.accel_m_s2 * (D - u);
  return c_.accel_m_s2 * ta;
}

double SimMobile::legDistance(double u, double D) const {
  const double a = c_.accel_m_s2;
  const double ta = std::min(c_.speed_m_s / a, D / 2), vp = a * ta;
  const double total = a * ta * ta + vp * (D - 2 * ta);
  u = std::clamp(u, 0.0, D);
  if (u < ta) return 0.5 * a * u * u;
  if (u <= D - ta) return 0.5 * a * ta * ta + vp * (u - ta);
  return total - 0.5 * a * (D - u) * (D - u);
}

double SimMobile::speedAt(double t) const {
  double start, length;
  int64_t k;
  legAt(t, &start, &length, &k);
  return legSpeed(t - start, length);
}

double SimMobile::accelerationAt(double t) const {
  double start, length;
  int64_t k;
  legAt(t, &start, &length, &k);
  const double u = t - start, ta = std::min(c_.speed_m_s / c_.accel_m_s2, length / 2);
  return (u > 0 && u < ta) ? c_.accel_m_s2 : (u > length - ta && u < length) ? -c_.accel_m_s2 : 0.0;
}

double SimMobile::distanceAt(double t) const {
  double start, length;
  int64_t k;
  legAt(t, &start, &length, &k);
  const double before =
      k > 0 ? static_cast<double>(k) * legDistance(c_.stop_interval_s, c_.stop_interval_s) : 0.0;
  return before + legDistance(t - start, length);
}

Pose2 SimMobile::roomPoseAt(double t) const { return path_.poseAt(s0_ + distanceAt(t)); }

Pose2 SimMobile::worldPoseAt(double t) const {
  const Pose2 r = roomPoseAt(t);
  const double c = std::cos(start_room_.theta_rad), s = std::sin(start_room_.theta_rad);
  const double dx = r.x_m - start_room_.x_m, dy = r.y_m - start_room_.y_m;
  return {c * dx + s * dy, -s * dx + c * dy, r.theta_rad - start_room_.theta_rad};
}

double SimMobile::turnRateAt(double t) const {
  return speedAt(t) * path_.curvatureAt(s0_ + distanceAt(t));
}

double SimMobile::wheelTurnedAt(double t, bool right) const {
  const auto ground = [&](double tt) {
    const double dtheta = roomPoseAt(tt).theta_rad - start_room_.theta_rad;
    return distanceAt(tt) + (right ? 0.5 : -0.5) * trueWheelDistance() * dtheta;
  };
  double d = ground(t);
  for (const SlipEvent& e : slips_) {
    if (e.right != right || t <= e.start_s) continue;
    d += e.fraction * (ground(std::min(t, e.end_s)) - ground(e.start_s));
  }
  return d;
}

Eigen::Isometry3d SimMobile::T_room_world() const { return planar(start_room_); }

std::vector<WheelTicks> SimMobile::wheelTicks() {
  std::mt19937_64 rng(streamSeed(seed_, Stream::kWheels));
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<WheelTicks> out;
  // Ticks per metre of ground: each wheel's true radius.
  const double per_m[2] = {
      wheels_.ticks_per_revolution / (2.0 * M_PI * wheels_.radiusOf(false, c_)),
      wheels_.ticks_per_revolution / (2.0 * M_PI * wheels_.radiusOf(true, c_))};
  double meas[2] = {0, 0}, prev[2] = {0, 0};
  for (int64_t k = 0;; ++k) {
    const double t = static_cast<double>(k) / c_.wheel_ticks_rate_hz;
    if (t > c_.duration_s + 1e-9) break;
    WheelTicks w{utimeAt(t), 0, 0};
    for (int side = 0; side < 2; ++side) {
      const double turned = wheelTurnedAt(t, side == 1);
      const double noise = 1.0 + c_.encoder_speed_sigma_fraction * n(rng);
      meas[side] += (turned - prev[side]) * noise;
      prev[side] = turned;
      const int64_t ticks = static_cast<int64_t>(std::floor(meas[side] * per_m[side] + 1e-9));
      (side == 0 ? w.left : w.right) = ticks;
    }
    out.push_back(w);
  }
  return out;
}

std::vector<ImuSample> SimMobile::imu() {
  std::mt19937_64 rng(streamSeed(seed_, Stream::kImu));
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<ImuSample> out;
  const double T = c_.duration_s;
  for (int64_t k = 0;; ++k) {
    const double t = static_cast<double>(k) / c_.imu_rate_hz;
    if (t > T + 1e-9) break;
    ImuSample m{};
    m.utime = utimeAt(t);
    const double v = speedAt(t), w = turnRateAt(t);
    const double dv = accelerationAt(t);
    m.gyro[0] = c_.gyro_sigma_rad_s * n(rng);
    m.gyro[1] = c_.gyro_sigma_rad_s * n(rng);
    m.gyro[2] = w + c_.gyro_bias_z_rad_s + c_.gyro_sigma_rad_s * n(rng);
    m.accel[0] = dv + c_.accel_sigma_m_s2 * n(rng);
    m.accel[1] = v * w + c_.accel_sigma_m_s2 * n(rng);
    m.accel[2] = kGravity + c_.accel_sigma_m_s2 * n(rng);
    const double sa = c_.attitude_sigma_deg * kDegToRad;
    m.rpy[0] = c_.roll_error_deg * kDegToRad + sa * n(rng);
    m.rpy[1] = c_.pitch_error_deg * kDegToRad + sa * n(rng);
    m.rpy[2] = wrapAngle(worldPoseAt(t).theta_rad + c_.yaw_error_deg * kDegToRad + sa * n(rng));
    out.push_back(m);
  }
  return out;
}

Scan2D SimMobile::makeScan(int64_t j, std::mt19937_64* rng, const BeamOffset& beam) const {
  std::normal_distribution<double> n(0.0, 1.0);
  SceneArtefacts artefacts = artefacts_;
  artefacts.reseed(streamSeed(seed_, Stream::kArtefacts) ^
                   (static_cast<uint64_t>(j) * 0xd1b54a32d192ed03ULL));
  Scan2D scan;
  scan.seq = j;
  // Stamped by the lidar's clock, which runs lidar_time_offset_ms ahead.
  const int64_t offset_us = std::llround(c_.lidar_time_offset_ms * 1000.0);
  scan.utime = utimeAt(static_cast<double>(j) / c_.scan_rate_hz) + offset_us;
  scan.angle_min_rad = -M_PI;
  scan.angle_increment_rad = 2.0 * M_PI / rays_;
  scan.time_increment_ns = std::llround(1e9 / c_.sample_rate_hz);
  scan.range_min_m = c_.range_min_m;
  scan.range_max_m = c_.range_max_m;
  scan.ranges_m.resize(static_cast<size_t>(rays_));
  if (beam) scan.angles_rad.resize(static_cast<size_t>(rays_));
  // The true hits first (the scene, then its artefacts: a window or a dark or grazed surface
  // returns nothing, a person or the whiteboard comes first), then the mixed pixels at the
  // depth edges between neighbouring rays, then the range noise.
  std::vector<BeamHit> hits(static_cast<size_t>(rays_));
  for (int i = 0; i < rays_; ++i) {
    const int64_t ray_utime = scan.rayUtime(static_cast<size_t>(i)) - offset_us;
    const double t = 1e-6 * static_cast<double>(ray_utime - start_utime_);
    const Eigen::Isometry3d T_room_L = planar(roomPoseAt(t)) * T_BL_;
    const Eigen::Vector3d origin = T_room_L.translation();
    const auto range_at = [&](double ang) {
      const Eigen::Vector3d dir =
          T_room_L.linear() * Eigen::Vector3d(0.0, std::sin(ang), std::cos(ang));
      Scene::Hit what;
      std::optional<double> hit = scene_->raycast(origin, dir, c_.range_max_m, &what);
      if (hit && !artefacts.returns(origin + *hit * dir, dir, what)) hit = 0.0;
      const double limit_m = hit && *hit > 0.0 ? *hit : c_.range_max_m;
      if (const auto object = artefacts.raycastObjects(origin, dir, limit_m, ray_utime)) {
        hit = object;
      }
      return hit.value_or(0.0);
    };
    const double motor = scan.angle_min_rad + scan.angle_increment_rad * i;
    hits[static_cast<size_t>(i)] =
        beam ? castBeam(motor, beam, range_at) : BeamHit{motor, range_at(motor)};
  }
  std::vector<double> ranges(hits.size());
  for (size_t i = 0; i < hits.size(); ++i) ranges[i] = hits[i].range_m;
  artefacts.mixEdges(&ranges);
  for (size_t i = 0; i < hits.size(); ++i) {
    const double noise = n(*rng);
    double r = 0.0;
    if (ranges[i] > 0.0) {
      r = ranges[i] * (1.0 + c_.range_sigma_fraction * noise);
      if (r < c_.range_min_m || r > c_.range_max_m) r = 0.0;
    }
    scan.ranges_m[i] = static_cast<float>(r);
    if (beam) {
      const double motor = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(i);
      scan.angles_rad[i] = static_cast<float>(wrapAngle(r > 0.0 ? hits[i].bearing_rad : motor));
    }
  }
  return scan;
}

std::vector<Scan2D> SimMobile::scans() {
  std::mt19937_64 rng(streamSeed(seed_, Stream::kLidar));
  std::vector<Scan2D> out;
  const double scan_span = (rays_ - 1) / c_.sample_rate_hz;
  for (int64_t j = 0;; ++j) {
    const double t = static_cast<double>(j) / c_.scan_rate_hz;
    if (t + scan_span > c_.duration_s + 1e-9) break;
    out.push_back(makeScan(j, &rng));
  }
  return out;
}

int64_t SimMobile::scanDeliveryUtime(const Scan2D& scan) const {
  return scan.rayUtime(scan.ranges_m.empty() ? 0 : scan.ranges_m.size() - 1) +
         static_cast<int64_t>(std::llround(c_.lidar_latency_ms * 1000.0));
}

std::vector<TruthPose> SimMobile::truth() const {
  std::vector<TruthPose> out;
  for (int64_t k = 0;; ++k) {
    const double t = static_cast<double>(k) / c_.truth_rate_hz;
    if (t > c_.duration_s + 1e-9) break;
    out.push_back({utimeAt(t), worldPoseAt(t), speedAt(t), turnRateAt(t), c_.gyro_bias_z_rad_s});
  }
  return out;
}

std::vector<std::string> paperMobileSettings() {
  std::vector<std::string> s = {"sim.wheel_radius_left_error_fraction=0",
                                "sim.wheel_radius_right_error_fraction=0",
                                "sim.wheel_distance_error_m=0",
                                "sim.lever_error_x_m=0",
                                "sim.lever_error_y_m=0",
                                "sim.lever_error_z_m=0",
                                "sim.lidar_time_offset_ms=0"};
  for (const std::string& a : SceneArtefactConfig::artefactsOff()) s.push_back(a);
  return s;
}

}  // namespace sweepmap
