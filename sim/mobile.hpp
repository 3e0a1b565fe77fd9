// Simulated rig B (Miao 2022): a differential-drive car with wheel encoders, an HI219-like
// IMU and a vertical YDLIDAR X4-like 2D lidar, driving a known path through a Scene.
// Transport-free: it produces plain structs; tools/sim_mobile.cpp turns them into messages.
//
// Frames.
//  - Room frame (sim/scene.hpp): origin on the floor at the room's centre, Z up.
//  - Body frame B: origin on the floor under the axle's midpoint, x forward, y left, z up;
//    the body's xOy plane is the floor, so the lidar's height h is mounting z_m.
//  - World frame W (the odometry's): the body frame at the start of the run. TRUTH_POSE is
//    the true body pose in W, the same frame as ODOMETRY_POSE / WHEEL_ODOMETRY.
//  - Lidar frame L: rays along (0, sin a, cos a), a measured from Z_L toward Y_L. With the
//    nominal mounting rpy = (0, 0, 0), Z_L is up (angle from the vertical, as the X4 on the
//    car) and the scan plane is the body's y-z plane: vertical and perpendicular to the
//    driving direction. The true T_BL is R(sim gamma, beta, alpha) R_nominal with the
//    position (l1 = x_m, y_m, h = z_m), nominal and position from the rig's mounting.*.
//
// Motion: speed ramps up at sim.accel_m_s2 to sim.speed_m_s, holds, and ramps down to stop
// at sim.duration_s; with sim.stop_interval_s > 0 the car also stops after each such leg of
// driving for sim.stop_duration_s (a rest in which the gyro reads its bias alone). The pose
// follows the path by arc length (exact, no integration).
//
// Randomness: independent std::mt19937_64 streams per device derived from the seed, so a
// device's draws do not depend on the others' settings. Same seed -> same output.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/config.hpp"
#include "core/rig_components.hpp"
#include "core/scan.hpp"
#include "devices/odometry_devices.hpp"
#include "odometry/wheel_odometry.hpp"
#include "sim/artefacts.hpp"
#include "sim/beam.hpp"
#include "sim/scene.hpp"

namespace sweepmap {

// The scene's artefacts (SceneArtefactConfig, the same sim.* keys as rig A's) come with the
// rest: mixed pixels at depth edges, dropouts on the dark table and cabinet and at grazing
// incidence, people walking through the lab, a window, a whiteboard.
struct SimMobileConfig : SceneArtefactConfig {
  std::string path = "circle";      // "circle", "loop", "figure8" or "file"
  std::string path_file;            // path: file — YAML of segments (MobilePath::fromFile)
  double circle_radius_m = 0.83;    // Miao 2022 calibration drive
  double circle_center_x_m = -3.0;  // room frame
  double circle_center_y_m = 0.0;
  double loop_wall_clearance_m = 0.5;  // loop: rounded rectangle this far from the walls
  double loop_corner_radius_m = 0.5;
  // figure8: two lobes of this radius, their centres this far apart along the room's X,
  // joined by straights that cross at the centre (left and right turns, and straights).
  double figure8_radius_m = 0.8;
  double figure8_lobe_spacing_m = 2.4;
  double figure8_center_x_m = -2.5;  // room frame
  double figure8_center_y_m = 0.0;
  double speed_m_s = 0.2;
  double accel_m_s2 = 0.5;
  double duration_s = 60.0;
  double stop_interval_s = 0.0;  // > 0: drive legs this long (ramps included), then stop
  double stop_duration_s = 3.0;  // each stop's rest
  // Wheels and encoders (radius, ticks per turn, wheel distance: the rig's odometry.*).
  double wheel_ticks_rate_hz = 50.0;
  double encoder_speed_sigma_fraction = 0.01;  // white, per reading
  double slip_mean_interval_s = 10.0;          // exponential; <= 0: no slip
  double slip_min_duration_s = 0.2;
  double slip_max_duration_s = 0.5;
  double slip_min_fraction = 0.1;  // the slipping wheel turns this much faster
  double slip_max_fraction = 0.3;
  // IMU (HI219-like).
  double imu_rate_hz = 200.0;
  double gyro_sigma_rad_s = 0.005;
  double gyro_bias_z_rad_s = 0.01;  // constant; x and y are unbiased
  double accel_sigma_m_s2 = 0.05;
  double roll_error_deg = 0.3;  // static attitude errors of the IMU's own estimate
  double pitch_error_deg = -0.2;
  double yaw_error_deg = 0.5;
  double attitude_sigma_deg = 0.05;
  // Lidar (YDLIDAR X4-like).
  double scan_rate_hz = 7.0;
  double sample_rate_hz = 5000.0;  // rays per second; rays per scan = round(sample / scan)
  double range_min_m = 0.12;
  double range_max_m = 10.0;
  double range_sigma_fraction = 0.01;  // sigma of the range noise, fraction of the range
  double lidar_latency_ms = 10.0;      // delivery after the last ray
  // True mounting error (the rig's mounting.* gamma/beta/alpha is what processes believe).
  // A real build's errors (issue 23): what the rig file's nominal values miss.
  double wheel_radius_left_error_fraction = 0.008;    // true left radius = nominal (1 + this)
  double wheel_radius_right_error_fraction = -0.011;  // true right radius
  double wheel_distance_error_m = 0.004;              // true track = nominal + this
  double lever_error_x_m = 0.003;  // true lidar centre = mounting.x_m/y_m/z_m + these
  double lever_error_y_m = -0.002;
  double lever_error_z_m = 0.004;
  double lidar_time_offset_ms = 3.0;  // the lidar's stamps run this far ahead of the odometry's
  double gamma_true_rad = 0.0355;
  double beta_true_rad = 0.0126;
  double alpha_true_rad = -0.0058;
  double truth_rate_hz = 100.0;

  void declare(ConfigSchema& s, const std::string& prefix);
  void validate(const std::string& source) const;  // throws ConfigError
};

// A planar path of straight lines and arcs, parametrised by arc length, closed (periodic).
class MobilePath {
 public:
  struct Segment {
    double x0, y0, theta0;  // start pose
    double length;
    double curvature;  // 1/m, + = left turn
  };
  explicit MobilePath(std::vector<Segment> segments);
  static MobilePath circle(double cx, double cy, double radius);
  static MobilePath roundedRectangle(double x_min, double x_max, double y_min, double y_max,
                                     double corner_radius);
  // Two lobes of `radius` with centres `spacing` apart along X about (cx, cy), joined by
  // two straights crossing at (cx, cy): a right turn round the +X lobe, a left turn round
  // the -X lobe. Starts at the centre. Requires spacing > 2 radius.
  static MobilePath figureEight(double cx, double cy, double radius, double spacing);
  // Segments chained from a start pose: each (length, curvature) begins where the last ends.
  static MobilePath chained(double x, double y, double theta,
                            const std::vector<std::pair<double, double>>& length_curvature);
  // A path from a YAML file, in the room frame:
  //   start: {x_m: -4.0, y_m: -2.0, heading_deg: 0}
  //   segments:
  //     - {length_m: 8.0}                  # straight
  //     - {length_m: 0.785, radius_m: 0.5} # arc; radius > 0 turns left, < 0 right
  // Throws ConfigError naming the file and the segment for a missing or bad value.
  static MobilePath fromFile(const std::string& file);
  // Whether the end pose meets the start (a loop the car may drive round more than once).
  bool closed() const;
  // Pose at arc length s (any s >= 0; wraps), heading unwrapped (grows by 2 pi per lap).
  Pose2 poseAt(double s) const;
  double curvatureAt(double s) const;
  double length() const { return length_; }

 private:
  const Segment& find(double s, double* local, int* lap) const;
  std::vector<Segment> segments_;
  std::vector<double> starts_;
  double length_ = 0.0;
  double turn_per_lap_ = 0.0;
};

// The `sim.*` settings of Miao 2022's model: a real build's odometry and lever errors off (the
// car's odometry exact, as the paper takes it when it calibrates the mounting alone) and no
// scene artefacts: the paper's experiment and the benchmark of its single-parameter
// `calib mounting`.
std::vector<std::string> paperMobileSettings();

struct TruthPose {
  int64_t utime;
  Pose2 pose;  // body in W
  double v_m_s, w_rad_s, gyro_bias_rad_s;
};
struct SlipEvent {
  double start_s, end_s;
  bool right;       // which wheel
  double fraction;  // reads this much fast
};

struct WheelGeometry {
  double radius_m = 0.0325;
  double radius_right_m = 0.0;  // the right wheel's nominal radius; 0: radius_m
  double ticks_per_revolution = 2000;
  double wheel_distance_m = 0.2;
  // The true wheels of a simulated car: the nominal geometry with its build errors.
  double radiusOf(bool right, const SimMobileConfig& c) const {
    const double nominal = right && radius_right_m > 0.0 ? radius_right_m : radius_m;
    return nominal * (1.0 + (right ? c.wheel_radius_right_error_fraction
                                   : c.wheel_radius_left_error_fraction));
  }
};

class SimMobile {
 public:
  // Throws ConfigError for an invalid configuration. The lidar sits at `t_BL_m` with the
  // nominal rotation (roll, pitch, yaw) `nominal_rpy_rad`, times the true error of `config`:
  // R = R(gamma, beta, alpha) R(nominal), R(g, b, a) = Rz(a) Ry(b) Rx(g)
  // (calib/world_assembly.hpp).
  SimMobile(const SimMobileConfig& config, const WheelGeometry& wheels,
            const Eigen::Vector3d& nominal_rpy_rad, const Eigen::Vector3d& t_BL_m,
            const Scene& scene, uint64_t seed, int64_t start_utime);

  // Truth at time t [s since start].
  double speedAt(double t) const;
  double accelerationAt(double t) const;  // along the path
  double distanceAt(double t) const;      // arc length driven
  Pose2 roomPoseAt(double t) const;       // body in the room
  Pose2 worldPoseAt(double t) const;      // body in W
  double turnRateAt(double t) const;
  // Distance the wheel's rim has turned through (ground distance plus slip).
  double wheelTurnedAt(double t, bool right) const;
  Eigen::Isometry3d T_room_world() const;
  Eigen::Isometry3d trueT_BL() const { return T_BL_; }
  double trueWheelDistance() const { return wheels_.wheel_distance_m + c_.wheel_distance_error_m; }
  const WheelGeometry& nominalWheels() const { return wheels_; }

  // Each device's whole output for the run, in time order.
  std::vector<WheelTicks> wheelTicks();
  std::vector<ImuSample> imu();
  std::vector<Scan2D> scans();  // Scan2D::utime = first ray
  std::vector<TruthPose> truth() const;
  const std::vector<SlipEvent>& slips() const { return slips_; }
  int64_t scanDeliveryUtime(const Scan2D& scan) const;
  // One scan (index j; j < 0: before the start, the car at rest) with the given noise
  // generator (the artefacts' draws come from a generator of the seed and j, so that a scan
  // made alone is the same scan as in the whole run). Its rays are the motor's angles on the grid;
  // with a beam offset each ray looks where castBeam says (Scan2D::angles_rad: where each looked; a
  // return outside the range limits after the noise becomes no return, along the motor angle).
  Scan2D makeScan(int64_t j, std::mt19937_64* rng, const BeamOffset& beam = nullptr) const;
  // The index of the last scan begun at or before `utime` (negative before the start).
  int64_t scanIndexAt(int64_t utime) const {
    return static_cast<int64_t>(
        std::floor(static_cast<double>(utime - start_utime_) * 1e-6 * c_.scan_rate_hz));
  }
  int raysPerScan() const { return rays_; }
  const SimMobileConfig& config() const { return c_; }
  int64_t utimeAt(double t) const {
    return start_utime_ + static_cast<int64_t>(std::llround(t * 1e6));
  }

 private:
  void legAt(double t, double* start, double* length, int64_t* index) const;
  double legSpeed(double u, double duration) const;
  double legDistance(double u, double duration) const;

  SimMobileConfig c_;
  WheelGeometry wheels_;
  const Scene* scene_;
  MobilePath path_;
  double s0_ = 0.0;  // arc length of the start pose on the path
  Pose2 start_room_;
  Eigen::Isometry3d T_BL_;
  std::vector<SlipEvent> slips_;
  uint64_t seed_;
  int64_t start_utime_;
  int rays_;
  SceneArtefacts artefacts_;  // reseeded per scan (makeScan: a copy)
};

}  // namespace sweepmap
