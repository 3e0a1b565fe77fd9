// Rig C's devices (Zhao 2021) and their simulation: a line-structured-light profile sensor
// on a turntable with an encoder, scanning a calibration plate in m poses or the paper's test
// piece. The configs of the sensor and the turntable are those a real driver will use; the
// simulator adds the truth (sim.*): the true offsets M, N, the laser plane's tilt, the
// encoder's zero, quantisation and noise, and the range noise.
//
// Each profile point comes from a ray of the laser's fan (apex: the sensor origin, in the
// laser plane, the columns evenly spaced in fan angle) meeting the scene; its range gets
// N(0, range_noise_sigma_mm) along the ray, and it is valid between near_mm and far_mm below
// the sensor. The encoder count latched with a profile is the true angle, quantised, with
// N(0, encoder_noise_counts) noise. The artefacts of a real part (sim/artefacts.hpp's physics):
// mixed pixels where neighbouring columns' ranges differ by more than 0.5 mm (a groove's rim:
// the line's spot falls on both surfaces), dropouts at glancing incidence (a groove's walls)
// and on dark or specular spots of the surface (any column). Randomness: std::mt19937_64
// streams derived from the seed (one for ranges, one for the encoder, one for the artefacts,
// drawn only where an artefact applies), so the same seed gives the same profiles.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/profile.hpp"
#include "core/profile_geometry.hpp"

namespace sweepmap {

// The profile sensor (a laser line profiler; config/rig_c.yaml says which and why).
struct ProfilerConfig {
  int column_count = 1280;    // points per full profile
  double near_mm = 190.0;     // nearest measurable distance below the sensor's origin
  double far_mm = 400.0;      // farthest
  double fov_far_mm = 194.0;  // length of the laser line at far_mm (the fan's width)
  double profile_rate_hz = 170.0;
  std::string device = "sim";  // the sensor the driver opens (only `sim` so far)
  void declare(ConfigSchema& s, const std::string& prefix);
  double fanHalfAngleRad() const;
};

// A flat face fixed to the turntable's base (a fence or stop, or the plate laid against one)
// whose normal's horizontal direction is known by construction: it defines the rig frame's
// X_r, which the encoder zero is measured from. Its normal leans normal_tilt_deg from vertical
// towards normal_azimuth_deg (from X_r, counter-clockwise seen from above).
struct TurntableReference {
  bool declared = true;             // false: the base has none (the zero is not observable)
  double normal_azimuth_deg = 0.0;  // by construction
  double normal_tilt_deg = 30.0;    // nominal; recognises the face's sweep
  double azimuth_sigma_deg = 0.02;  // how well construction fixes the azimuth
  void declare(ConfigSchema& s, const std::string& prefix);
};

// The turntable and its encoder, and the sweep it makes per recording.
struct TurntableConfig {
  int counts_per_revolution = 262144;  // encoder counts per turn
  double speed_deg_s = 20.0;
  double sweep_start_deg = -25.0;  // turntable angle (encoder, before its zero) of a sweep's start
  double sweep_end_deg = 25.0;
  std::string device = "sim";
  TurntableReference reference;
  void declare(ConfigSchema& s, const std::string& prefix);
};

// The paper's test piece (Zhao 2021 Fig. 7, Table 2's CMM sizes): a block whose top face
// holds, along the scanning direction, a round groove, a rectangular groove and a round groove.
struct TestPieceConfig {
  double distance_mm = 300.0;       // top face below the sensor's origin
  double block_length_mm = 260.0;   // along the scanning direction
  double block_width_mm = 160.0;    // along the laser line
  double spacing_mm = 80.0;         // centre to centre of neighbouring grooves
  double left_diameter_mm = 50.01;  // round groove (first along the scan)
  double left_depth_mm = 30.03;
  double right_diameter_mm = 50.02;
  double right_depth_mm = 30.02;
  double rect_length_mm = 39.99;  // along the scanning direction
  double rect_width_mm = 80.03;   // along the laser line
  double rect_depth_mm = 20.01;
  void declare(ConfigSchema& s, const std::string& prefix);
};

struct SimProfileConfig {
  std::string scene = "plate";  // plate (m poses, one sweep each) | test_piece (one sweep)
  double offset_m_mm = 123.0;   // true M, N (Zhao 2021 Table 1)
  double offset_n_mm = 409.0;
  double laser_tilt_deg = 0.2;    // true tilt of the laser plane from the axis
  double encoder_zero_deg = 0.5;  // true turntable angle at encoder count 0
  double encoder_noise_counts = 0.5;
  double range_noise_sigma_mm = 0.02;
  // The artefacts (0: none; the paper models none).
  double mixed_pixel_probability = 0.5;       // a column at a depth edge returns a range between
  double dropout_glancing_probability = 0.5;  // no return at 90 deg incidence (from 70 deg)
  double dropout_spot_probability = 0.01;     // no return from a dark or specular spot
  int plate_count = 3;                        // m, the plate's poses (one sweep each)
  double plate_size_mm = 250.0;               // square plate
  double plate_distance_mm = 300.0;           // plate centre below the sensor's origin
  double plate_distance_step_mm = 40.0;       // pose k's centre: distance + step * (k mod 3 - 1)
  double plate_tilt_deg = 30.0;               // plate normal from vertical
  double plate_tilt_spread_deg = 360.0;  // tilt directions spread evenly over this; 0: parallel
  double pause_s = 1.0;                  // between sweeps (the plate is moved)
  // The plate scene ends with a sweep over the base's reference face (turntable.reference),
  // whose normal truly leans towards this azimuth (its construction error against the
  // declared one); tilt and size as declared and as the plate's.
  bool reference_sweep = false;
  double reference_azimuth_deg = 0.01;
  TestPieceConfig test_piece;
  void declare(ConfigSchema& s, const std::string& prefix);
  ProfileGeometry trueGeometry() const;
  // The settings of the artefacts' keys that switch them off, and the same on this struct.
  static std::vector<std::string> artefactsOff();
  void switchArtefactsOff();
};

// The plate of one sweep: a square of side `size` centred at `centre`, in frame O_r.
struct PlatePose {
  Eigen::Vector3d centre, normal, e1, e2;  // e1, e2: in-plane unit axes
  double half_size_mm = 0.0;
  double distance() const { return normal.dot(centre); }  // n . p = d on the plate
};

// The plate poses of sim.* (plate_count of them), each under the middle of the sweep, then
// the base's reference face when sim.reference_sweep.
std::vector<PlatePose> platePoses(const SimProfileConfig& sim, const TurntableConfig& turntable);
// The base's reference face (turntable.reference) at its true azimuth
// (sim.reference_azimuth_deg), under the middle of the sweep at the plate's distance.
PlatePose referencePose(const SimProfileConfig& sim, const TurntableConfig& turntable);

// What the laser meets: a set of plates or the test piece; distance along a ray.
class ProfileScene {
 public:
  static ProfileScene plate(const PlatePose& pose);
  static ProfileScene testPiece(const SimProfileConfig& sim, const TurntableConfig& turntable);
  // The test piece's frame in O_r (u along the line, v along the scan, w up; origin at the
  // top face's centre); unset for a plate.
  struct Frame {
    Eigen::Vector3d origin, u, v, w;
  };
  std::optional<Frame> testPieceFrame() const;
  // The first surface from `origin` along the unit `dir`, if any: its distance [mm] and its
  // unit normal (either sign).
  struct Hit {
    double range_mm = 0.0;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  };
  std::optional<Hit> cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const;

 private:
  std::optional<PlatePose> plate_;
  // Test piece in its own frame (u along the line, v along the scan, w up; origin at the
  // top face's centre), and that frame in O_r.
  bool test_piece_ = false;
  TestPieceConfig piece_;
  Eigen::Vector3d origin_, u_, v_, w_;
  std::optional<Hit> castTestPiece(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const;
};

// The simulated sensor and turntable. profile() is the physics of one exposure, shared by the
// offline simulation (sweep(): a whole sweep at constant speed) and the live simulated
// devices (sim/profile_devices.hpp: the turntable as commanded).
class SimProfiler {
 public:
  SimProfiler(const ProfilerConfig& profiler, const TurntableConfig& turntable,
              const SimProfileConfig& sim, uint64_t seed);
  // Every profile of one sweep from `start_utime`, in time order.
  std::vector<Profile> sweep(const ProfileScene& scene, int32_t sweep_id, int64_t start_utime);
  // Duration of one sweep [us].
  int64_t sweepDurationUs() const;
  // One exposure at `utime` of `scene` with the turntable at the true encoder angle
  // `encoder_rad` (before its zero): the points the laser meets, with range noise, and the
  // encoder count latched (noise, then quantised). Draws from the seed's streams in order.
  Profile profile(const ProfileScene& scene, double encoder_rad, int64_t utime, int32_t sweep_id);

 private:
  ProfilerConfig profiler_;
  TurntableConfig turntable_;
  SimProfileConfig sim_;
  ProfileGeometry truth_;
  std::mt19937_64 range_rng_, encoder_rng_, artefact_rng_;
  std::normal_distribution<double> normal_;
  int64_t sequence_ = 0;
};

}  // namespace sweepmap
