// The components of a rig description (lidar, motor, geometry, plate, assembler, mapper,
// simulated errors), as read by the processes and tools. One struct per component;
// `declare` binds every field to its dotted config key so a rig YAML file is loaded
// strictly (see core/config.hpp). The rig kinds that combine them are in rigs/.
#pragma once

#include <string>
#include <vector>

#include "core/config.hpp"

namespace sweepmap {

struct LidarConfig {
  // The device, from the catalogue of core/lidar_models.hpp (UST-10LX, URG-04LX-UG01,
  // YDLIDAR-X4, ...). The keys below must fit it: for a SCIP model they pick the run of its
  // steps the driver requests (the field of view), and the driver checks the device's PP.
  std::string model = "UST-10LX";
  int beam_count = 1081;          // rays per scan
  double angle_min_deg = -135.0;  // angle of ray 0, from Z_L toward Y_L
  double angle_increment_deg = 0.25;
  double scan_rate_hz = 40.0;
  int steps_per_revolution = 1440;  // ray slots per mirror turn: sets the per-ray time
  double range_min_m = 0.06;
  double range_max_m = 10.0;
  // Which lidar the lidar process opens (drivers/device_uri.hpp): sim | scip://HOST[:PORT] |
  // ydlidar:///dev/PORT | rplidar:///dev/PORT[?baud=N]. `sweepmap-lidar --device` overrides.
  std::string device = "sim";
  void declare(ConfigSchema& s, const std::string& prefix);
  // Throws ConfigError naming `source` and the key.
  void validate(const std::string& source, const std::string& prefix) const;
  double rayPeriodS() const { return 1.0 / (scan_rate_hz * steps_per_revolution); }
};

struct MotorConfig {
  int mode = 7;                    // scan mode 1..7 of Yuan 2021 Table 1
  double sweep_angle_deg = 180.0;  // rotation during the lidar window
  double accel_deg_s2 = 720.0;     // nominal ramp acceleration
  double margin_s = 0.1;  // constant-speed time before the window opens and after it closes
  double move_speed_deg_s = 90.0;  // speed of positioning and return moves
  double homing_speed_deg_s = 20.0;
  double homing_search_deg = 400.0;  // give up homing after this much travel
  double home_angle_deg = 0.0;       // shaft angle at which the switch edge is defined
  std::string action_sequence =
      "improved";  // improved (Fig. 2) | naive (lidar and motor start together)
  bool rehome_every_sweep = true;
  double pause_s = 0.5;   // standstill between sweeps
  double settle_s = 0.2;  // wait after a move's nominal end before the next
  double status_rate_hz = 10.0;
  // Which stepper the motor process drives (core/device_uri.hpp): sim |
  // gpiod://CHIP?step=N&dir=N&enable=N&home=N[&...]. `sweepmap-motor --sim` forces sim.
  std::string device = "sim";
  int steps_per_rev = 200;          // full steps per shaft turn (1.8 deg motor: 200)
  int microsteps = 16;              // as set on the driver board (MS1..MS3)
  double switch_debounce_ms = 2.0;  // home switch level must hold this long to count
  void declare(ConfigSchema& s, const std::string& prefix);
  // Throws ConfigError naming `source` and the key.
  void validate(const std::string& source, const std::string& prefix) const;
  double stepAngleDeg() const { return 360.0 / (double(steps_per_rev) * microsteps); }
};

struct GeometryConfig {
  double lidar_offset_x_mm = 13.9;  // t_L^O' = (offset, 0, 0), Eq. 5-6
  // R_L^O' (Eq. 5-6; the paper's I): the scan plane tilted against the rotation axis (about
  // Y_L: its normal X_L leans toward Z by this angle) and the mirror's angle zero offset (about
  // X_L: a ray reported at theta leaves at theta + mirror_offset). rotating::lidarRotation.
  double scan_plane_tilt_deg = 0.0;
  double mirror_offset_deg = 0.0;
  // Calibration file (relative to the rig file) whose geometry.lidar_offset_x_mm replaces
  // lidar_offset_x_mm (sweepmap calib axis-offset); empty: use lidar_offset_x_mm.
  std::string calibration_file;
  void declare(ConfigSchema& s, const std::string& prefix);
};

struct PlateConfig {
  double alpha_deg = 30.0;  // angle of the plate's middle line from X (front)
  // Calibration file (relative to the rig file) whose plate.alpha_deg replaces alpha_deg;
  // empty: use alpha_deg.
  std::string calibration_file;
  double height_mm = -45.0;   // z of the plate's upper surface in frame O
  double thickness_mm = 2.0;  // the plate's solid reaches this far below its upper surface
  double region_inner_radius_mm = 62.5;
  double region_outer_radius_mm = 115.5;
  double region_thickness_mm = 20.0;  // centred on height_mm
  double hypotenuse_mm = 112.0;       // isosceles right triangle: legs 79.2 mm
  double base_distance_mm = 54.75;    // hypotenuse to rotation axis
  int min_points = 30;                // fewer points: the sweep is left uncorrected
  // How beta is estimated: "centroid" (Yuan 2021: mean of the points in the region) or
  // "ray_plane" (each ray that meets the plate plane inside the region and whose range
  // agrees within range_gate_mm contributes its noise-free intersection point).
  std::string beta_method = "ray_plane";
  double range_gate_mm = 30.0;
  void declare(ConfigSchema& s, const std::string& prefix);
};

struct AssemblerConfig {
  int chunk_points = 4000;       // points per SWEEP_CLOUD message (one UDP datagram)
  int max_pending_scans = 4000;  // bounded scan buffer
  bool correct_attitude = true;  // apply the plate correction (false: publish C_O')
  void declare(ConfigSchema& s, const std::string& prefix);
};

struct MapperConfig {
  double resolution_m = 0.05;
  double max_range_m = 10.0;  // rays longer than this are cut (free space only)
  double prob_hit = 0.7;
  double prob_miss = 0.4;
  double clamp_min = 0.12;
  double clamp_max = 0.97;
  // Rig B only (key mapper.batch_s of a rig-B file; rig A inserts every sweep on its own):
  // sweeps whose time falls in the same batch_s window of message time are inserted with
  // one update of the tree's inner nodes (OccupancyMap::insertClouds; same map). 0: each
  // sweep on its own.
  double batch_s = 0.0;
  // Bounds: sweeps being assembled (the oldest goes into the map as it is, counted as
  // incomplete, when one is reached), and MAP_SAVE requests from the network (rate, names).
  int max_pending_sweeps = 4;
  int max_pending_points = 4'000'000;  // 48 MB of xyz floats
  double save_interval_s = 1.0;        // at most one MAP_SAVE honoured per this long
  int max_requested_files = 16;        // names a run's MAP_SAVE requests may create
  void declare(ConfigSchema& s, const std::string& prefix);
  // Throws ConfigError naming `path` and the key of a bound that is not positive.
  void validateBounds(const std::string& path, const std::string& prefix) const;
};

// Bounds of a live process's receive path (keys network.* of every rig file): its queue of
// messages for the nodes, and the reassembly of fragmented LCM datagrams
// (net/lcm_datagram.hpp). What a bound refuses is counted in the nodes' status (`dropped`,
// `net_refused_<reason>`).
struct NetworkConfig {
  int queue_messages = 10000;
  double queue_mib = 64.0;
  double max_message_mib = 16.0;        // a fragmented message's declared size
  int pending_messages_per_sender = 4;  // messages being reassembled, per sender
  double pending_mib_per_sender = 24.0;
  double pending_mib = 64.0;  // all senders together
  int max_senders = 64;       // senders with messages being reassembled
  double fragment_timeout_s =
      1.0;  // an unfinished message expires this long after its last fragment
  void declare(ConfigSchema& s, const std::string& prefix);
  void validate(const std::string& path, const std::string& prefix) const;
};

// The real-scene artefacts a calibration must survive (sim/artefacts.hpp), in the room of the
// simulated lidar of rig A and rig B: the same sim.* keys and defaults for both.
struct SceneArtefactConfig {
  double mixed_pixel_probability = 0.5;       // a ray at a depth edge returns a range in between
  double dropout_dark_probability = 0.3;      // no return from dark furniture (table, cabinet)
  double dropout_glancing_probability = 0.5;  // no return at grazing incidence (rising from 70 deg)
  int people = 2;                             // people walking through the room during the sweeps
  double window_width_m = 1.5;                // a window (glass: no return) in the -Y wall; 0: none
  // A whiteboard this far proud of the -X wall (of the +X wall where the scene's calibration
  // target is on the -X wall); 0: none.
  double whiteboard_proud_mm = 20;
  void declareArtefacts(ConfigSchema& s, const std::string& prefix);
  // The settings of the keys above that switch every artefact off (the papers model none).
  static std::vector<std::string> artefactsOff();
  // The same on this struct.
  void switchArtefactsOff();
};

// Error model of the simulated rig A (Yuan 2021 section 2). Read by the simulator only.
struct SimRigConfig : SceneArtefactConfig {
  double alpha_true_deg = 29.3598;     // true plate angle (installation error vs plate.alpha_deg)
  double lidar_offset_x_mm = 13.9;     // true lidar-to-axis offset
  double range_noise_sigma_mm = 12.0;  // UST-10LX: +-40 mm read as ~3.3 sigma
  double accel_jitter = 0.1;           // ramp acceleration varies uniformly by +-this fraction
  double start_delay_max_ms = 30.0;    // motor starts 0..max ms after its command
  double switch_response_ms = 2.0;     // mean response time of the photoelectric switch
  double switch_response_jitter_ms = 1.0;  // uniform +- jitter of the response time
  double switch_hysteresis_deg = 0.3;      // edge moves by this when approached from the other side
  double lidar_latency_ms = 50.0;          // a scan is delivered this long after its last ray
  // A real build (not in the paper's model; its experiment sets them to 0: paperSettings()).
  double scan_plane_tilt_deg = 0.3;  // true tilt of the scan plane against the axis (about Y_L)
  double mirror_offset_deg = 0.2;    // true mirror angle zero offset (about X_L)
  double plate_thickness_mm = 2.0;   // true plate: a solid this thick below its upper surface
  void declare(ConfigSchema& s, const std::string& prefix);
  // The paper's settings of the keys above (Yuan 2021 models none of them: all 0).
  static std::vector<std::string> paperSettings();
  // The same on this struct.
  void applyPaperSettings();
};

// Table 1 of Yuan 2021: 3D scan time T [s] and angular step gamma [deg] of modes 1..7.
struct ScanMode {
  int mode;
  double period_s;
  double gamma_deg;
};
ScanMode scanMode(int mode);  // throws std::out_of_range for a mode outside 1..7

}  // namespace sweepmap
