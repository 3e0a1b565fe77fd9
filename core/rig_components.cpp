#include "core/rig_components.hpp"

#include <algorithm>
#include <stdexcept>

#include "core/device_uri.hpp"
#include "core/lidar_models.hpp"

namespace sweepmap {

void LidarConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "model", &model, "",
        "the lidar model (core/lidar_models.hpp): " + lidarModelNames() +
            "; the keys below must fit it, and a SCIP driver requests just their steps");
  s.add(p + "beam_count", &beam_count, "", "rays per scan");
  s.add(p + "angle_min_deg", &angle_min_deg, "deg", "angle of ray 0, from Z_L toward Y_L");
  s.add(p + "angle_increment_deg", &angle_increment_deg, "deg", "angle between rays");
  s.add(p + "scan_rate_hz", &scan_rate_hz, "Hz", "scans per second");
  s.add(p + "steps_per_revolution", &steps_per_revolution, "",
        "ray slots per mirror turn (sets the time between rays)");
  s.add(p + "range_min_m", &range_min_m, "m", "shortest valid range");
  s.add(p + "range_max_m", &range_max_m, "m", "longest valid range");
  s.add(p + "device", &device, "",
        "the lidar to open: sim | scip://HOST[:PORT] | scip:///dev/PORT[?baud=N] (a Hokuyo "
        "on a serial or USB port) | ydlidar:///dev/PORT | rplidar:///dev/PORT[?baud=N]");
}

void LidarConfig::validate(const std::string& source, const std::string& p) const {
  const auto require = [&](bool ok, const std::string& key, const std::string& what) {
    if (!ok) throw ConfigError(source + ": key '" + p + key + "' " + what);
  };
  require(beam_count > 0, "beam_count", "must be > 0");
  require(scan_rate_hz > 0, "scan_rate_hz", "must be > 0");
  require(steps_per_revolution >= beam_count, "steps_per_revolution", "must be >= beam_count");
  require(range_min_m >= 0 && range_max_m > range_min_m, "range_max_m",
          "must exceed range_min_m >= 0");
  DeviceUri uri;
  try {
    uri = parseDeviceUriFor(
        device, {DeviceProtocol::kScip, DeviceProtocol::kYdlidarX4, DeviceProtocol::kRplidar});
  } catch (const std::invalid_argument& e) {
    throw ConfigError(source + ": key '" + p + "device': " + e.what());
  }
  const LidarModel* m = findLidarModel(model);
  require(m != nullptr, "model", "'" + model + "' is not one of " + lidarModelNames());
  require(uri.protocol == DeviceProtocol::kSim || uri.protocol == m->protocol, "device",
          "speaks " + std::string(protocolName(uri.protocol)) + ", the " + model + " " +
              protocolName(m->protocol));
  try {
    checkLidarFitsModel(*this, *m);
  } catch (const LidarFitError& e) {
    throw ConfigError(source + ": key '" + p + e.key + "' " + e.what());
  }
}

void MotorConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "mode", &mode, "", "scan mode 1..7 (Yuan 2021 Table 1)");
  s.add(p + "sweep_angle_deg", &sweep_angle_deg, "deg", "rotation while the lidar window is open");
  s.add(p + "accel_deg_s2", &accel_deg_s2, "deg/s^2", "nominal ramp acceleration");
  s.add(p + "margin_s", &margin_s, "s",
        "constant-speed time before the window opens and after it closes");
  s.add(p + "move_speed_deg_s", &move_speed_deg_s, "deg/s", "speed of positioning moves");
  s.add(p + "homing_speed_deg_s", &homing_speed_deg_s, "deg/s", "speed while seeking the switch");
  s.add(p + "homing_search_deg", &homing_search_deg, "deg", "travel before homing gives up");
  s.add(p + "home_angle_deg", &home_angle_deg, "deg", "shaft angle of the switch edge");
  s.add(p + "action_sequence", &action_sequence, "",
        "improved (motor runs before and after the lidar window) or naive");
  s.add(p + "rehome_every_sweep", &rehome_every_sweep, "", "seek the switch before every sweep");
  s.add(p + "pause_s", &pause_s, "s", "standstill between sweeps");
  s.add(p + "settle_s", &settle_s, "s", "wait after a move's nominal end before the next");
  s.add(p + "status_rate_hz", &status_rate_hz, "Hz", "MOTOR_STATE publication rate");
  s.add(p + "device", &device, "",
        "the stepper to drive: sim | gpiod://CHIP?step=N&dir=N&enable=N&home=N[&enable_active="
        "low|high&dir_positive=high|low&home_blocked=high|low&home_pull=up|down|none]");
  s.add(p + "steps_per_rev", &steps_per_rev, "", "full steps per shaft turn (1.8 deg motor: 200)");
  s.add(p + "microsteps", &microsteps, "", "microsteps per full step, as set on the driver board");
  s.add(p + "switch_debounce_ms", &switch_debounce_ms, "ms",
        "gpiod: the home switch's level must hold this long before an edge counts");
}

void MotorConfig::validate(const std::string& source, const std::string& p) const {
  const auto require = [&](bool ok, const std::string& key, const std::string& what) {
    if (!ok) throw ConfigError(source + ": key '" + p + key + "' " + what);
  };
  require(mode >= 1 && mode <= 7, "mode", "must be 1..7");
  require(sweep_angle_deg > 0, "sweep_angle_deg", "must be > 0");
  require(accel_deg_s2 > 0, "accel_deg_s2", "must be > 0");
  require(move_speed_deg_s > 0, "move_speed_deg_s", "must be > 0");
  require(homing_speed_deg_s > 0, "homing_speed_deg_s", "must be > 0");
  require(homing_search_deg > 0, "homing_search_deg", "must be > 0");
  require(margin_s >= 0, "margin_s", "must be >= 0");
  require(settle_s >= 0 && pause_s >= 0, "settle_s", "and pause_s must be >= 0");
  require(status_rate_hz > 0, "status_rate_hz", "must be > 0");
  require(action_sequence == "improved" || action_sequence == "naive", "action_sequence",
          "must be improved or naive");
  require(steps_per_rev >= 1 && steps_per_rev <= 100000, "steps_per_rev", "must be 1..100000");
  require(microsteps >= 1 && microsteps <= 256 && (microsteps & (microsteps - 1)) == 0,
          "microsteps", "must be a power of two, 1..256");
  require(switch_debounce_ms >= 0 && switch_debounce_ms <= 100, "switch_debounce_ms",
          "must be in [0, 100]");
  // The generator's pulses (5 us high, 5 us low) and a Pi's GPIO writes allow far more, but a
  // stepper driver at this rate has lost its load long before: a typing error.
  const double fastest_deg_s =
      std::max({sweep_angle_deg / scanMode(mode).period_s, move_speed_deg_s, homing_speed_deg_s});
  require(fastest_deg_s / stepAngleDeg() <= 50000, "microsteps",
          "with steps_per_rev gives over 50000 steps/s at the fastest configured speed (" +
              std::to_string(fastest_deg_s) + " deg/s)");
  try {
    parseDeviceUriFor(device, {DeviceProtocol::kGpiod});
  } catch (const std::invalid_argument& e) {
    throw ConfigError(source + ": key '" + p + "device': " + e.what());
  }
}

void GeometryConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "lidar_offset_x_mm", &lidar_offset_x_mm, "mm",
        "distance of the scan plane from the rotation axis (t_L^O')");
  s.add(p + "calibration_file", &calibration_file, "",
        "calibration YAML (relative to the rig file) whose geometry.lidar_offset_x_mm replaces "
        "lidar_offset_x_mm (sweepmap calib axis-offset); empty: none");
  s.add(p + "scan_plane_tilt_deg", &scan_plane_tilt_deg, "deg",
        "scan plane tilted against the rotation axis (about Y_L; sweepmap calib rig)");
  s.add(p + "mirror_offset_deg", &mirror_offset_deg, "deg",
        "the lidar's angle zero offset: a ray reported at theta leaves at theta + this (about "
        "X_L; sweepmap calib rig)");
}

void PlateConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "alpha_deg", &alpha_deg, "deg", "plate middle line from the front (X) axis");
  s.add(p + "calibration_file", &calibration_file, "",
        "calibration YAML (relative to the rig file) whose plate.alpha_deg replaces alpha_deg; "
        "empty: none");
  s.add(p + "height_mm", &height_mm, "mm", "z of the plate surface in frame O");
  s.add(p + "thickness_mm", &thickness_mm, "mm",
        "plate thickness below its surface (beta_method model: its inner edge's face)");
  s.add(p + "region_inner_radius_mm", &region_inner_radius_mm, "mm", "semi-ring inner radius");
  s.add(p + "region_outer_radius_mm", &region_outer_radius_mm, "mm", "semi-ring outer radius");
  s.add(p + "region_thickness_mm", &region_thickness_mm, "mm", "semi-ring thickness about height");
  s.add(p + "hypotenuse_mm", &hypotenuse_mm, "mm", "plate hypotenuse (isosceles right triangle)");
  s.add(p + "base_distance_mm", &base_distance_mm, "mm", "hypotenuse to rotation axis");
  s.add(p + "min_points", &min_points, "", "fewest plate points for a correction");
  s.add(p + "beta_method", &beta_method, "",
        "centroid (Yuan 2021), ray_plane (rays meeting the plate plane in the region) or model "
        "(the plate's solid model, cast along the same rays: no sampling bias; calib/plate_model)");
  s.add(p + "range_gate_mm", &range_gate_mm, "mm",
        "ray_plane: largest |measured - plane range| of a plate ray");
}

void AssemblerConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "chunk_points", &chunk_points, "", "points per SWEEP_CLOUD message");
  s.add(p + "max_pending_scans", &max_pending_scans, "", "scan buffer bound (older dropped)");
  s.add(p + "correct_attitude", &correct_attitude, "",
        "apply the plate correction (false: publish the uncorrected cloud C_O')");
}

void MapperConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "resolution_m", &resolution_m, "m", "OctoMap voxel size");
  s.add(p + "max_range_m", &max_range_m, "m", "rays are cut at this range");
  s.add(p + "prob_hit", &prob_hit, "", "sensor model: occupancy probability of a hit");
  s.add(p + "prob_miss", &prob_miss, "", "sensor model: occupancy probability of a miss");
  s.add(p + "clamp_min", &clamp_min, "", "lower clamping threshold");
  s.add(p + "clamp_max", &clamp_max, "", "upper clamping threshold");
  s.add(p + "max_pending_sweeps", &max_pending_sweeps, "",
        "sweeps being assembled at once; beyond, the oldest goes into the map as it is "
        "(`incomplete_sweeps`)");
  s.add(p + "max_pending_points", &max_pending_points, "",
        "points held in sweeps being assembled (12 bytes each); beyond, as above");
  s.add(p + "save_interval_s", &save_interval_s, "s",
        "at most one MAP_SAVE request honoured per this long (`refused_saves`)");
  s.add(p + "max_requested_files", &max_requested_files, "",
        "map files MAP_SAVE requests may create in a run (`refused_saves`)");
}

namespace {
void requirePositive(bool ok, const std::string& path, const std::string& key) {
  if (!ok) throw ConfigError(path + ": key '" + key + "' must be > 0");
}
}  // namespace

void MapperConfig::validateBounds(const std::string& path, const std::string& p) const {
  requirePositive(max_pending_sweeps > 0, path, p + "max_pending_sweeps");
  requirePositive(max_pending_points > 0, path, p + "max_pending_points");
  requirePositive(save_interval_s > 0, path, p + "save_interval_s");
  requirePositive(max_requested_files > 0, path, p + "max_requested_files");
}

void NetworkConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "queue_messages", &queue_messages, "",
        "receive queue bound in messages (--queue-capacity overrides it); a message that finds "
        "it full is dropped (`dropped`)");
  s.add(p + "queue_mib", &queue_mib, "MiB", "receive queue bound in bytes, as above");
  s.add(p + "max_message_mib", &max_message_mib, "MiB",
        "largest fragmented LCM message accepted (`net_refused_message_too_large`)");
  s.add(p + "pending_messages_per_sender", &pending_messages_per_sender, "",
        "fragmented messages being reassembled per sender (`net_refused_sender_limit`)");
  s.add(p + "pending_mib_per_sender", &pending_mib_per_sender, "MiB",
        "fragment bytes held per sender (`net_refused_sender_limit`)");
  s.add(p + "pending_mib", &pending_mib, "MiB",
        "fragment bytes held for all senders (`net_refused_memory_limit`)");
  s.add(p + "max_senders", &max_senders, "",
        "senders with messages being reassembled (`net_refused_sender_limit`)");
  s.add(p + "fragment_timeout_s", &fragment_timeout_s, "s",
        "an unfinished message expires this long after its last fragment "
        "(`net_refused_timed_out`)");
}

void NetworkConfig::validate(const std::string& path, const std::string& p) const {
  requirePositive(queue_messages > 0, path, p + "queue_messages");
  requirePositive(queue_mib > 0, path, p + "queue_mib");
  // A fragmented message is at most 2^28 bytes on LCM's wire (liblcm's own bound).
  if (!(max_message_mib > 0 && max_message_mib <= 256)) {
    throw ConfigError(path + ": key '" + p + "max_message_mib' must be in (0, 256]");
  }
  requirePositive(pending_messages_per_sender > 0, path, p + "pending_messages_per_sender");
  requirePositive(pending_mib_per_sender > 0, path, p + "pending_mib_per_sender");
  requirePositive(pending_mib > 0, path, p + "pending_mib");
  requirePositive(max_senders > 0, path, p + "max_senders");
  requirePositive(fragment_timeout_s > 0, path, p + "fragment_timeout_s");
}

void SimRigConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "alpha_true_deg", &alpha_true_deg, "deg", "true plate angle (installation error)");
  s.add(p + "lidar_offset_x_mm", &lidar_offset_x_mm, "mm", "true lidar-to-axis offset");
  s.add(p + "range_noise_sigma_mm", &range_noise_sigma_mm, "mm", "Gaussian range noise");
  s.add(p + "accel_jitter", &accel_jitter, "", "ramp acceleration varies by +- this fraction");
  s.add(p + "start_delay_max_ms", &start_delay_max_ms, "ms",
        "motor starts uniformly 0..max after its command (lidar/motor start deviation)");
  s.add(p + "switch_response_ms", &switch_response_ms, "ms", "home switch mean response time");
  s.add(p + "switch_response_jitter_ms", &switch_response_jitter_ms, "ms",
        "home switch response jitter (uniform +-)");
  s.add(p + "switch_hysteresis_deg", &switch_hysteresis_deg, "deg",
        "switch edge shift between the two approach directions");
  s.add(p + "lidar_latency_ms", &lidar_latency_ms, "ms", "delivery delay after a scan's last ray");
  s.add(p + "scan_plane_tilt_deg", &scan_plane_tilt_deg, "deg",
        "true tilt of the scan plane against the rotation axis (about Y_L)");
  s.add(p + "mirror_offset_deg", &mirror_offset_deg, "deg",
        "true offset of the lidar's angle zero (about X_L)");
  s.add(p + "plate_thickness_mm", &plate_thickness_mm, "mm",
        "true plate thickness below its upper surface");
  declareArtefacts(s, p);
}

void SceneArtefactConfig::declareArtefacts(ConfigSchema& s, const std::string& p) {
  s.add(p + "mixed_pixel_probability", &mixed_pixel_probability, "",
        "a ray at a depth edge returns a range between the two surfaces");
  s.add(p + "dropout_dark_probability", &dropout_dark_probability, "",
        "no return from dark furniture (table, cabinet)");
  s.add(p + "dropout_glancing_probability", &dropout_glancing_probability, "",
        "no return at 90 deg incidence (0 up to 70 deg, linear between)");
  s.add(p + "people", &people, "", "people walking through the room (moving boxes)");
  s.add(p + "window_width_m", &window_width_m, "m",
        "a window (no return) in the -Y wall, this wide; 0: none");
  s.add(p + "whiteboard_proud_mm", &whiteboard_proud_mm, "mm",
        "a whiteboard this far proud of the -X wall (of the +X wall where the scene's "
        "calibration target is on the -X wall); 0: none");
}

std::vector<std::string> SceneArtefactConfig::artefactsOff() {
  return {"sim.mixed_pixel_probability=0",
          "sim.dropout_dark_probability=0",
          "sim.dropout_glancing_probability=0",
          "sim.people=0",
          "sim.window_width_m=0",
          "sim.whiteboard_proud_mm=0"};
}

void SceneArtefactConfig::switchArtefactsOff() {
  mixed_pixel_probability = dropout_dark_probability = dropout_glancing_probability = 0.0;
  people = 0;
  window_width_m = whiteboard_proud_mm = 0.0;
}

std::vector<std::string> SimRigConfig::paperSettings() {
  std::vector<std::string> s = {"sim.scan_plane_tilt_deg=0", "sim.mirror_offset_deg=0",
                                "sim.plate_thickness_mm=0"};
  for (const std::string& a : artefactsOff()) s.push_back(a);
  return s;
}

void SimRigConfig::applyPaperSettings() {
  scan_plane_tilt_deg = mirror_offset_deg = plate_thickness_mm = 0.0;
  switchArtefactsOff();
}

ScanMode scanMode(int mode) {
  static const ScanMode kModes[] = {{1, 1.0, 4.5},     {2, 2.0, 2.25},   {3, 4.0, 1.125},
                                    {4, 5.0, 0.9},     {5, 8.0, 0.5625}, {6, 10.0, 0.45},
                                    {7, 16.0, 0.28125}};
  if (mode < 1 || mode > 7) throw std::out_of_range("scan mode must be 1..7");
  return kModes[mode - 1];
}

}  // namespace sweepmap
