// `sweepmap calib <what>`: calibrate the rig from its own logs: `plate-angle` (rig A, Yuan
// 2021 section 4.2, Algorithm A1), `mounting` (rig B, Miao 2022 section 4.2) and
// `axis-offset` (rig C, Zhao 2021; rig A's lidar-to-axis offset by the same plane
// constraint). The workflows are in tools/offline/calibrate_*.hpp.
#include <iostream>
#include <memory>

#include "core/command_line.hpp"
#include "rigs/rig_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/offline/calibrate_axis_offset.hpp"
#include "tools/offline/calibrate_lidar_axis_offset.hpp"
#include "tools/offline/calibrate_mounting.hpp"
#include "tools/offline/calibrate_plate.hpp"
#include "tools/offline/calibrate_rig.hpp"

namespace sweepmap {
namespace {

// `calib plate-angle`: its flags into a PlateAngleCalibRequest.
CLI::App* addPlateAngle(CLI::App* calib, std::shared_ptr<PlateAngleCalibRequest> o) {
  auto* plate = calib->add_subcommand("plate-angle",
                                      "rotating_lidar rigs (rig A): calibrate the triangular "
                                      "plate's installation angle alpha (Yuan 2021 section 4.2, "
                                      "Algorithm A1) from sweeps of a rectangular room");
  plate->footer(
      "Each corrected sweep's four walls are extracted (voxel grid, then RANSAC vertical planes: "
      "two facing pairs, perpendicular), and alpha minimises F_cost = 1/2 sum_m f_cost(alpha)^2 "
      "by Levenberg-Marquardt (Algorithm A1: alpha_0 = 30 deg, tau = 1e-6, eps1 = eps2 = 1e-9, "
      "k_max = 500), f_cost summing how far each wall normal is from perpendicular to its axis "
      "(Eq. 16). Record many sweeps of the highest resolution mode (the paper: 50 in mode 7) with "
      "the rig standing square to the room's walls.\n\n"
      "Writes OUT atomically (plate.alpha_deg + provenance); set plate.calibration_file in the "
      "rig file to use it. Uncorrected sweeps (no plate, motor ramp) and sweeps without four "
      "walls are rejected and listed. Human report (per sweep, result, timing) on stderr; --json "
      "prints alpha_deg, iterations, final_cost, converged, sweeps_used, sweeps_rejected, history "
      "and, for simulated logs, alpha_true_deg on stdout.\n\n"
      "Exit status: 0 calibrated; 1 a log is corrupt or holds no usable sweep; 2 bad option or "
      "rig, a missing log, or an output folder that does not exist; 4 OUT cannot be written.\n"
      "Example: sweepmap calib plate-angle --logs room.lcmlog --rig rig_a "
      "--out config/plate_calibration.yaml");
  plate->add_option("--logs", o->logs, "LCM logs of the room (sweepmap sim, lcm-logger)")
      ->required()
      ->expected(1, -1)
      ->check(CLI::ExistingFile);
  plate
      ->add_option("--rig", o->rig, "rig file or name (rotating_lidar) the logs were recorded with")
      ->required();
  plate->add_option("--out", o->out, "calibration file to write (YAML, atomically)")->required();
  plate->add_flag("--json", o->json, "print the result as JSON on stdout");
  plate->add_option("--set", o->sets, "override a rig config key: key=value (repeatable)");
  plate->add_option("--voxel", o->voxel_m, "voxel size [m] of the wall extraction's downsampling")
      ->capture_default_str()
      ->check(greaterThan(0));
  return plate;
}

// `calib mounting`: its flags into a MountingCalibRequest.
CLI::App* addMounting(CLI::App* calib, std::shared_ptr<MountingCalibRequest> m) {
  auto* mount = calib->add_subcommand(
      "mounting",
      "mobile_lidar rigs (rig B): calibrate the lidar's 3-axis mounting error (gamma about body x, "
      "beta about y, "
      "alpha about z; Miao 2022 section 4.2) from a drive that sees the same surfaces twice "
      "(the circle of `sweepmap sim --rig rig_b`, a calibration target in view)");
  mount->footer(
      "The log's wheel and IMU messages are replayed through the odometry node (EKF) for the "
      "track; every lidar ray is placed in the world with the pose at its own time. On a circle a "
      "place is seen by one half of the scan and, half a turn later, by the other: the two "
      "passes.\n\n"
      "Ours (the result written): Ceres over all overlapping points of the two passes, each "
      "point of one pass against the local plane of the other pass there (PCA of its neighbours; "
      "patches that are not flat to within the range noise, or where the point's own pass sees "
      "another plane, are skipped), both passes re-assembled with the mounting, Cauchy loss, "
      "correspondences found again each outer iteration; with --time-offset also the "
      "lidar-to-odometry time offset (unobservable on a steady circle, where it only turns the "
      "whole cloud: needs speed or curvature changes, e.g. the lab loop). The paper's (reported "
      "beside it): the calibration target's edge points found in every scan (a board: a run of "
      "rays 0.3-0.8 m long with a range jump to something farther at both ends, as the lab's "
      "board in front of its window), paired mutually nearest across the passes, "
      "Levenberg-Marquardt on their squared distances (Eq. 15-17).\n\n"
      "On a circle of radius R, alpha shows only as a shift of 2R alpha (1.7 mm per mrad at "
      "R = 0.83 m) between the passes, so the track's relative error over half a lap limits it: "
      "drive several laps (2 min: 4.6 laps at 0.2 m/s; measured on the simulator, EKF track, seeds "
      "1-5: |alpha error| <= 0.9 mrad with 2 min, up to 1.03 mrad with 1 min).\n\n"
      "Writes OUT atomically (mounting.gamma_rad/beta_rad/alpha_rad + provenance); set "
      "mounting.calibration_file in the rig file to use it. The search starts from the rig's "
      "mounting. Human report on stderr; --json prints gamma_rad, beta_rad, alpha_rad, "
      "time_offset_s (with --time-offset: each pose's time minus its ray's after the rig's "
      "lidar.time_offset_s; the rig's value less it is the new lidar.time_offset_s), "
      "sigma (the 1-sigma of each angle, and of time_offset_s with --time-offset, from the "
      "covariance, the rig's other values taken as exact), "
      "residual_before_m, residual_after_m (RMS), correspondences, method, the paper's result "
      "under \"paper\", warnings and, for simulated logs, the truth and "
      "error_mrad. Warns when the wheels disagree with the gyro (each radius over the track "
      "against the rig file's, beyond 3 sigma): the odometry track is then biased, and calib "
      "rig calibrates them together; and when the drive cannot check them (a steady circle).\n\n"
      "Exit status: 0 calibrated; 1 not calibrated (a corrupt log, too little data, no overlap); "
      "2 bad option or rig, a missing log, or an output folder that does not exist; 4 OUT cannot "
      "be written.\n"
      "Example: sweepmap sim --rig rig_b --set sim.duration_s=120 --out circle.lcmlog && "
      "sweepmap calib mounting --logs circle.lcmlog --rig rig_b --out "
      "config/mounting_calibration.yaml");
  mount->add_option("--logs", m->log, "LCM log of the drive (sweepmap sim, lcm-logger)")
      ->check(CLI::ExistingFile);
  // --log: its name before the other calib commands' --logs, kept as a hidden alias.
  mount->add_option("--log", m->log, "")->group("")->check(CLI::ExistingFile);
  mount->add_option("--rig", m->rig, "rig file or name (mobile_lidar) the log was recorded with")
      ->required();
  mount->add_option("--out", m->out, "calibration file to write (YAML, atomically)")->required();
  mount->add_flag("--json", m->json, "print the result as JSON on stdout");
  mount->add_option("--set", m->sets, "override a rig config key: key=value (repeatable)");
  mount
      ->add_option("--track", m->track,
                   "poses: ekf (ODOMETRY_POSE replayed), wheels, truth (simulated logs)")
      ->capture_default_str()
      ->check(CLI::IsMember({"ekf", "wheels", "truth"}));
  mount->add_flag("--time-offset", m->time_offset,
                  "also estimate the lidar-to-odometry time offset (ours)");
  mount->add_flag("--track-drift", m->track_drift,
                  "also estimate a slow drift (world velocity) of the track's position (ours; "
                  "odometry tracks)");
  mount->add_flag("--no-paper", m->no_paper, "skip the paper's method");
  mount
      ->add_option("--min-pass-gap", m->min_pass_gap_s,
                   "seconds between two observations of a place for them to be two passes")
      ->capture_default_str()
      ->check(greaterThan(0));
  return mount;
}

// What `calib axis-offset` does for each kind, for its --help.
const char* const kAxisOffsetFooter =
    "rotating_lidar (rig A): every sweep of the logs is assembled with the rig's offset "
    "(geometry.lidar_offset_x_mm, nominal 13.9 mm), its planes (walls, floor, ceiling, "
    "furniture) found by PCL RANSAC, each ray assigned to the plane whose crossing along "
    "the ray its range is within 50 mm of (none where another plane crosses the ray within 150 "
    "mm of it: edges; at most --plane-points per plane, evenly strided); then Ceres over the "
    "offset and every plane (unit normal + distance, each sweep "
    "its own), Cauchy-weighted point-to-plane residuals, reweighted three times. What planes "
    "can see: x (across the scan plane, the paper's 13.9 mm) and y (within it, perpendicular "
    "to the axis) bend the vertical walls and are observable from them; floor and ceiling "
    "constrain neither; z (along the axis) moves the whole cloud and is never observable (held "
    "at 0). x is estimated and written (geometry.lidar_offset_x_mm); --offset-y also estimates "
    "y, reported only (the rig's model has t = (x, 0, 0)). Warns, and writes nothing, when x "
    "is not determined (no vertical wall; sigma > 0.5 mm). The rig file's scan-plane tilt and "
    "mirror offset are held (placed with them). The rays within 2 beams and scans "
    "of a depth edge are left out, as calib rig does. Warns when the walls bend more than the "
    "noise, and when calib rig's joint model (the scan-plane tilt, the mirror offset, clutter), "
    "solved on the same sweeps as a check, puts x more than 3 sigma away. Prints the wall-plane "
    "RMS before "
    "(the rig's offset) and after (each plane refit by least squares); --json prints "
    "lidar_offset_x_mm, sigma_x_mm, observability {x, y, z}, wall_rms_before_mm, "
    "wall_rms_after_mm, planes, warnings and, for simulated logs, truth_x_mm and "
    "offset_error_mm. Record several sweeps of a room in a high-resolution mode (20 mode-7 "
    "sweeps: within 0.11 mm of a true 16 mm on five simulated seeds).\n\n"
    "rotating_profile (rig C): every turntable sweep of the logs is one pose of the plate "
    "(sweepmap sim --rig rig_c "
    "makes sim.plate_count of them; a real recording: one sweep per pose, the plate alone in "
    "view). Both methods see the same points (at most --max-points per sweep, evenly "
    "strided).\n\n"
    "The paper's (reported, and drawn as S(M, N) like its Fig. 6): points to frame O_r by "
    "Eq. 7, a least-squares plane z = Ax + By + C per pose (Eq. 8-13), the RMS of the "
    "point-to-plane distances (Eq. 14), their mean S (Eq. 15), minimised by a grid search of "
    "--m-min..--m-max x --n-min..--n-max in --step (Algorithm 1; default the paper's (110, 130) "
    "x (395, "
    "425) mm in 1 mm).\n\n"
    "Ours (the result written): Ceres over M, N and every plane (unit normal on the sphere + "
    "distance) with point-to-plane residuals through the generalised Eq. 7, also the laser "
    "plane's tilt from the axis (unless --no-tilt) and, with --encoder-zero, the encoder's "
    "zero; each parameter's standard deviation from J^T J with the planes eliminated. A parameter "
    "the planes "
    "do not determine is reported: the encoder zero is not unless a sweep over the base's "
    "reference face (turntable.reference) is among the logs (it turns the whole cloud about "
    "the axis) and is then held at the rig's value; M and N are not with parallel or level "
    "plates, and then nothing is written. Without --encoder-zero, a sweep over the reference "
    "face is still looked for: when it puts the zero more than 3 sigma from the rig's, a "
    "warning says so.\n\n"
    "Writes OUT atomically (axis_offset.m_mm, n_mm, laser_tilt_deg, encoder_zero_deg + "
    "provenance with the standard deviations and the paper's result); set "
    "geometry.calibration_file in the rig file to use it. Human report on stderr; --json "
    "prints ours, paper, warnings, planes and, for simulated logs, truth and offset_error_mm "
    "on stdout.\n\n"
    "Exit status: 0 calibrated; 1 not calibrated (no plate sweep or room plane, M, N or the "
    "lidar's offset not observable) or a bad log (no profiles, a non-finite point, a corrupt "
    "event: named with its byte offset); 2 bad option (or one of the other kind) or rig, a "
    "missing log, or an output folder that does not exist; 4 OUT cannot be written.\n"
    "Examples: sweepmap sim --rig rig_c --out plates.lcmlog && sweepmap calib axis-offset "
    "--logs plates.lcmlog --rig rig_c --out axis_offset.yaml\n"
    "sweepmap sim --rig rig_a --mode 7 --sweeps 20 --set sim.lidar_offset_x_mm=16 --out "
    "room.lcmlog && sweepmap calib axis-offset --logs room.lcmlog --rig rig_a --out "
    "lidar_offset.yaml";

void addAxisOffsetProfileOptions(CLI::App* axis, std::shared_ptr<AxisOffsetCalibRequest> a);
void addAxisOffsetLidarOptions(CLI::App* axis, std::shared_ptr<LidarAxisOffsetCalibRequest> l);

// `calib axis-offset`: its flags into an AxisOffsetCalibRequest (rig C) and a
// LidarAxisOffsetCalibRequest (rig A); the rig file's kind decides which runs.
CLI::App* addAxisOffset(CLI::App* calib, std::shared_ptr<AxisOffsetCalibRequest> a,
                        std::shared_ptr<LidarAxisOffsetCalibRequest> l) {
  auto* axis = calib->add_subcommand(
      "axis-offset",
      "rotating_profile and rotating_lidar rigs (C, A): the sensor's offset from its rotation "
      "axis by the plane constraint. rotating_profile rigs (rig C): calibrate the profile "
      "sensor's offsets M, N from the turntable's axis (Zhao 2021) from sweeps of a flat plate "
      "in m non-parallel poses; rotating_lidar rigs (rig A): the lidar's offset t_L^O' from its "
      "rotation axis from room sweeps, by the same plane constraint");
  axis->footer(kAxisOffsetFooter);

  axis->add_option("--logs", a->logs,
                   "LCM logs of the plate sweeps (rig C) or of a room (rig A) (sweepmap sim, "
                   "lcm-logger)")
      ->required()
      ->expected(1, -1)
      ->check(CLI::ExistingFile);
  axis->add_option("--rig", a->rig,
                   "rig file or name (rotating_profile or rotating_lidar) the logs were recorded "
                   "with")
      ->required();
  axis->add_option("--out", a->out, "calibration file to write (YAML, atomically)")->required();
  axis->add_flag("--json", a->json, "print the result as JSON on stdout");
  axis->add_option("--set", a->sets, "override a rig config key: key=value (repeatable)");
  addAxisOffsetProfileOptions(axis, a);
  addAxisOffsetLidarOptions(axis, l);
  return axis;
}

// `calib axis-offset`'s options for rotating_profile rigs (kProfileOnly below).
void addAxisOffsetProfileOptions(CLI::App* axis, std::shared_ptr<AxisOffsetCalibRequest> a) {
  axis->add_option("--m-min", a->grid.m_min_mm, "the paper's grid: M from [mm]")
      ->capture_default_str();
  axis->add_option("--m-max", a->grid.m_max_mm, "the paper's grid: M to [mm]")
      ->capture_default_str();
  axis->add_option("--n-min", a->grid.n_min_mm, "the paper's grid: N from [mm]")
      ->capture_default_str();
  axis->add_option("--n-max", a->grid.n_max_mm, "the paper's grid: N to [mm]")
      ->capture_default_str();
  axis->add_option("--step", a->grid.step_mm, "the paper's grid step [mm]")
      ->capture_default_str()
      ->check(greaterThan(0));
  axis->add_flag("--no-grid", a->no_grid, "skip the paper's method");
  axis->add_option("--figure", a->figure, "S(M, N) picture (PNG; default OUT's name + _S.png)");
  axis->add_flag(
      "--no-tilt", [a](int64_t) { a->estimate_tilt = false; },
      "ours: hold the laser plane's tilt at the rig's value");
  axis->add_flag(
      "--encoder-zero", a->estimate_encoder_zero,
      "ours: also estimate the encoder's zero (only against a sweep over the base's reference "
      "face, turntable.reference; else expect the warning)");
  axis->add_option("--max-points", a->max_points_per_sweep,
                   "points per sweep both methods use (evenly strided; 0 = all)")
      ->capture_default_str();
}

// `calib axis-offset`'s options for rotating_lidar rigs (kLidarOnly below).
void addAxisOffsetLidarOptions(CLI::App* axis, std::shared_ptr<LidarAxisOffsetCalibRequest> l) {
  axis->add_flag("--offset-y", l->estimate_y,
                 "rotating_lidar: also estimate the offset within the scan plane (reported)");
  axis->add_option("--plane-points", l->segmentation.max_rays_per_plane,
                   "rotating_lidar: points per plane and sweep (evenly strided; 0 = all)")
      ->capture_default_str()
      ->check(atLeast(0));
}

// The options of `calib axis-offset` that only one kind takes.
const std::vector<std::string> kProfileOnly = {
    "--m-min",   "--m-max",  "--n-min",   "--n-max",        "--step",
    "--no-grid", "--figure", "--no-tilt", "--encoder-zero", "--max-points"};
const std::vector<std::string> kLidarOnly = {"--offset-y", "--plane-points"};

// `calib axis-offset` by the rig's kind; an option of the other kind is an error (exit 2).
int runAxisOffset(CLI::App* axis, const AxisOffsetCalibRequest& a,
                  std::shared_ptr<LidarAxisOffsetCalibRequest> l) {
  RigKind kind;
  try {
    kind = readRigKind(resolveRigFile(a.rig));
  } catch (const std::exception& e) {
    std::cerr << "calib axis-offset: config error: " << e.what() << "\n";
    return kExitUsage;
  }
  const bool lidar = kind == RigKind::kRotatingLidar;
  for (const auto& name : lidar ? kProfileOnly : kLidarOnly) {
    if (axis->count(name) > 0) {
      std::cerr << "calib axis-offset: " << name << " is for "
                << (lidar ? "rotating_profile" : "rotating_lidar") << " rigs; " << a.rig << " is a "
                << rigKindName(kind) << " rig\n";
      return kExitUsage;
    }
  }
  if (!lidar) return calibrateAxisOffsetFromLogs(a);
  l->logs = a.logs;
  l->rig = a.rig;
  l->sets = a.sets;
  l->out = a.out;
  l->json = a.json;
  return calibrateLidarAxisOffsetFromLogs(*l);
}

// `calib rig`: its flags into a RigCalibRequest.
CLI::App* addRig(CLI::App* calib, std::shared_ptr<RigCalibRequest> r) {
  auto* rig = calib->add_subcommand(
      "rig",
      "calibrate every parameter of the rig that its logs make observable, jointly, into one "
      "calibration file the rig file points to (calibration_file, or geometry.calibration_file "
      "for rotating_profile)");
  rig->footer(
      "rotating_lidar (rig A): the plate angle alpha (plate.alpha_deg), the lidar-to-axis "
      "offset (geometry.lidar_offset_x_mm), the scan plane's tilt against the axis "
      "(geometry.scan_plane_tilt_deg) and the mirror's angle zero offset "
      "(geometry.mirror_offset_deg), in one Ceres least squares: every ray of the room's walls "
      "(RANSAC planes; the four walls facing +-X, +-Y fix each sweep's attitude) and of its "
      "other planes, Cauchy loss, clutter proud of a wall removed by 0.5 m cells and their "
      "neighbours, and per sweep the plate's solid model (plate.thickness_mm, its edge face) "
      "cast along the same rays as saw the plate (calib/plate_model.hpp). Each parameter's sigma "
      "and their correlation from the covariance (J^T J with the sweeps' attitudes and planes "
      "eliminated), grown by the design effect of what the walls' cells show beyond the noise; "
      "a parameter the logs do not determine is reported, left at the rig's "
      "value and not written. Warns when the residuals show an error the model lacks. Record "
      "what `sweepmap calib plan --rig RIG` says.\n\n"
      "rotating_profile (rig C): M, N (geometry.offset_m_mm, offset_n_mm), the laser plane's tilt "
      "(geometry.laser_tilt_deg) and the encoder zero (geometry.encoder_zero_deg) by the solver "
      "of `calib axis-offset` (Ceres over the four and every plate pose's plane; each turntable "
      "sweep is one pose). Plate poses cannot fix the encoder zero (a turn of the whole cloud "
      "about the axis); a sweep over the base's reference face does (turntable.reference: its "
      "normal's azimuth is known by construction), recognised by its plane's normal. Without "
      "it the zero is reported not observable and kept. OUT has the format of `calib "
      "axis-offset` (geometry.calibration_file applies it).\n\n"
      "mobile_lidar (rig B), in order: each wheel radius over the track and the gyro bias from "
      "the wheels against the gyro (straights, turns both ways, stops); then the distance "
      "driven (the wheels' common scale), the mounting angles, the lever arm's x and y and the "
      "lidar-odometry time offset in one least squares over the drive's passes over the same "
      "walls (each point against the plane of its 0.25 m patch, which both passes see, the "
      "plane eliminated; each sigma the larger of that solve's and point-to-plane's at the same "
      "solution), the odometry re-run with the corrected wheels; the lever arm's z from the "
      "floor; the room's length, width and height from its planes in the calibrated cloud "
      "(measures in --json). OUT holds every calibrated key (calibration_file applies it; the "
      "lidar's time offset is lidar.time_offset_s, the gyro bias the EKF starts from "
      "odometry.gyro_bias_rad_s). One drive: the first log.\n\n"
      "Writes OUT atomically (rigs A and B: parameters: rig-file keys; source: sigmas, "
      "residuals, logs) and prints the calibration_file line for the rig file, relative to its "
      "folder. The rig's plate.beta_method should be model so the assembler finds the plate as the "
      "calibration did. Human report and progress on stderr; --json prints {\"parameters\": "
      "{KEY: {value, sigma, unit, observable, nominal, truth (simulated logs)}}, \"measures\": "
      "{KEY: {value, unit, truth}} (rig B's room), \"warnings\": [...], correlation, residuals} "
      "on stdout.\n\n"
      "Exit status: 0 calibrated; 1 nothing calibrated (no usable sweep, nothing observable, a "
      "log that cannot be read); 2 bad option or rig, a missing log, or an output folder that does "
      "not exist; 4 OUT cannot be written.\n"
      "Example: sweepmap calib rig --rig rig_a --logs calib.lcmlog --out rig_calibration.yaml");
  rig->add_option("--logs", r->logs,
                  "LCM logs of the calibration recording (sweepmap sim, lcm-logger)")
      ->required()
      ->expected(1, -1);
  rig->add_option("--rig", r->rig, "rig file or name the logs were recorded with")->required();
  rig->add_option("--out", r->out, "calibration file to write (YAML, atomically)")->required();
  rig->add_flag("--json", r->json, "print the result as JSON on stdout (no progress)");
  rig->add_option("--set", r->sets, "override a rig config key: key=value (repeatable)");
  rig->add_option("--plane-points", r->segmentation.max_rays_per_plane,
                  "rays per plane and sweep at most (evenly strided)")
      ->capture_default_str()
      ->check(atLeast(10));
  return rig;
}

struct PlanRequest {
  std::string rig;
  std::vector<std::string> sets;
};

CLI::App* addPlan(CLI::App* calib, std::shared_ptr<PlanRequest> p) {
  auto* plan = calib->add_subcommand(
      "plan",
      "print what to record for `calib rig` (scene, sweeps or path, duration) and why, "
      "with the `sweepmap sim` command that makes that recording");
  plan->footer("Exit status: 0 printed; 2 bad option or rig.");
  plan->add_option("--rig", p->rig, "rig file or name")->required();
  plan->add_option("--set", p->sets, "override a rig config key: key=value (repeatable)");
  return plan;
}

}  // namespace

Runner addCalibCommand(CLI::App& app) {
  auto* calib = app.add_subcommand(
      "calib",
      "Calibrate the rig from its own logs and write the result as a calibration file the rig "
      "file points to. `rig` calibrates every parameter at once (every rig kind; `plan` says "
      "what to record for it); single parameters by the rig's kind: plate-angle (rotating_lidar), "
      "mounting (mobile_lidar), axis-offset (rotating_profile; rotating_lidar: the lidar-to-axis "
      "offset)");
  calib->require_subcommand(1);
  auto o = std::make_shared<PlateAngleCalibRequest>();
  auto m = std::make_shared<MountingCalibRequest>();
  CLI::App* plate = addPlateAngle(calib, o);
  CLI::App* mount = addMounting(calib, m);
  auto a = std::make_shared<AxisOffsetCalibRequest>();
  auto l = std::make_shared<LidarAxisOffsetCalibRequest>();
  l->segmentation.depth_edge_rays = kRigCalibDepthEdgeRays;
  CLI::App* axis = addAxisOffset(calib, a, l);
  auto r = std::make_shared<RigCalibRequest>();
  r->segmentation.max_rays_per_plane = kRigCalibPlaneRays;
  r->segmentation.depth_edge_rays = kRigCalibDepthEdgeRays;
  CLI::App* rig = addRig(calib, r);
  auto p = std::make_shared<PlanRequest>();
  CLI::App* plan = addPlan(calib, p);
  return [plate, o, mount, m, axis, a, l, rig, r, plan, p]() -> int {
    if (plan->parsed()) return printCalibrationPlan(p->rig, p->sets);
    if (rig->parsed()) {
      checkOutputFile(r->out, r->logs);
      return calibrateRigFromLogs(*r);
    }
    if (plate->parsed()) checkOutputFile(o->out, o->logs);
    if (mount->parsed()) checkOutputFile(m->out, {m->log});
    if (axis->parsed()) checkOutputFile(a->out, a->logs);
    if (plate->parsed()) return calibratePlateAngleFromLogs(*o);
    if (mount->parsed()) {
      if (m->log.empty()) throw ConfigError("calib mounting: --logs LOG is required");
      return calibrateMountingFromLog(*m);
    }
    if (axis->parsed()) return runAxisOffset(axis, *a, l);
    return kExitUsage;
  };
}

}  // namespace sweepmap
