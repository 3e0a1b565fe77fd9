// `sweepmap calib <what>`: calibrate the rig from its own logs: `plate-angle` (rig A, Yuan
// 2021 section 4.2, Algorithm A1) and `mounting` (rig B, Miao 2022 section 4.2).
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "calib/mounting_calibration.hpp"
#include "calib/plate_angle.hpp"
#include "calib/walls.hpp"
#include "core/calibration_file.hpp"
#include "core/event_log.hpp"
#include "rigs/rig_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/offline/log_sweeps.hpp"
#include "tools/offline/mobile_log.hpp"
#include "core/angles.hpp"

namespace sweepmap {
namespace {


struct PlateAngleOptions {
  std::vector<std::string> logs;
  std::string rig, out;
  std::vector<std::string> sets;
  bool json = false;
  double voxel_m = WallExtractionOptions{}.voxel_m;
};

std::string utcNow() {
  const std::time_t t = std::time(nullptr);  // provenance only: never used in a result
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

double seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

int runPlateAngle(const PlateAngleOptions& o) {
  using clock = std::chrono::steady_clock;
  const auto t_start = clock::now();
  RotatingLidarConfig rig;
  try {
    rig = requireKind<RotatingLidarConfig>(loadRig(o.rig, o.sets), "calib plate-angle");
  } catch (const std::exception& e) {
    std::cerr << "calib plate-angle: config error: " << e.what() << "\n";
    return 2;
  }
  for (const auto& log : o.logs) {
    if (!std::filesystem::is_regular_file(log)) {
      std::cerr << "calib plate-angle: log '" << log << "' does not exist or is not a file\n";
      return 2;
    }
  }
  const std::filesystem::path out_dir = std::filesystem::absolute(o.out).parent_path();
  if (!std::filesystem::is_directory(out_dir)) {
    std::cerr << "calib plate-angle: output directory '" << out_dir.string()
              << "' does not exist\n";
    return 2;
  }

  WallExtractionOptions wall_options;
  wall_options.voxel_m = o.voxel_m;
  std::vector<SweepNormals> sweeps;
  nlohmann::json rejected = nlohmann::json::array();
  nlohmann::json log_errors = nlohmann::json::array();
  std::optional<double> alpha_true_rad;
  double walls_s = 0, read_s = 0;
  int seen = 0;
  for (const auto& log : o.logs) {
    const auto t_log = clock::now();
    double walls_this_log_s = 0;
    LogReadResult r;
    try {
      r = forEachSweep(log, rig, [&](const AssembledSweep& s, const SweepTruth&) {
        ++seen;
        const auto reject = [&](const std::string& reason) {
          rejected.push_back({{"log", log}, {"id", s.window.sweep_id}, {"reason", reason}});
          std::cerr << "  " << log << " sweep " << s.window.sweep_id << ": rejected: " << reason
                    << "\n";
        };
        if (!s.corrected) return reject("not corrected: " + s.reason);
        const auto t0 = clock::now();
        const WallExtraction e = extractWalls(s.points, wall_options);
        walls_this_log_s += seconds(clock::now() - t0);
        if (e.walls.empty()) return reject("walls: " + e.reason);
        SweepNormals n;
        n.alpha_used_rad = s.alpha_rad;
        for (const auto& w : e.walls) n.normals.push_back(w.normal);
        std::cerr << "  " << log << " sweep " << s.window.sweep_id << ": 4 walls, E_atti "
                  << std::setprecision(4) << attitudeError(n) << " at alpha "
                  << std::setprecision(8) << s.alpha_rad * kRadToDeg << " deg\n";
        sweeps.push_back(std::move(n));
      });
    } catch (const LogError& e) {
      std::cerr << "calib plate-angle: cannot read log '" << log << "': " << e.what() << "\n";
      return 2;
    }
    walls_s += walls_this_log_s;
    read_s += seconds(clock::now() - t_log) - walls_this_log_s;
    if (r.log_error) {
      std::cerr << "calib plate-angle: " << r.error << " (the sweeps before it are used)\n";
      log_errors.push_back({{"log", log}, {"error", r.error}});
    }
    if (r.alpha_true_rad && !alpha_true_rad) alpha_true_rad = r.alpha_true_rad;
  }

  if (sweeps.empty()) {
    std::cerr << "calib plate-angle: no usable sweep (" << seen << " seen, " << rejected.size()
              << " rejected) in " << o.logs.size() << " log(s): nothing calibrated\n";
    if (o.json) {
      std::cout << nlohmann::json{{"sweeps_used", 0},
                                  {"sweeps_rejected", rejected},
                                  {"log_errors", log_errors}}
                       .dump(2)
                << "\n";
    }
    return 1;
  }

  const auto t_lm = clock::now();
  LmOptions lm;  // Algorithm A1's parameters; alpha_0 = 30 deg as in the paper
  const LmResult result = calibratePlateAngle(sweeps, lm);
  const double lm_s = seconds(clock::now() - t_lm);
  double e_before = 0, e_after = 0;
  for (const auto& s : sweeps) {
    e_before += attitudeError(s);
    e_after += fCost(s, result.alpha_rad);
  }
  e_before /= sweeps.size();
  e_after /= sweeps.size();
  const double alpha_deg = result.alpha_rad * kRadToDeg;

  PlateCalibration c;
  c.alpha_deg = alpha_deg;
  c.source["tool"] = "sweepmap calib plate-angle";
  c.source["date"] = utcNow();
  c.source["sweeps_used"] = std::to_string(sweeps.size());
  std::ostringstream cost;
  cost << std::setprecision(6) << result.final_cost;
  c.source["final_cost"] = cost.str();
  c.source["iterations"] = std::to_string(result.iterations);
  c.source["converged"] = result.converged ? "true" : "false";
  c.logs = o.logs;
  writePlateCalibration(o.out, c);
  const double total_s = seconds(clock::now() - t_start);

  std::cerr << std::setprecision(8) << "calib plate-angle: alpha = " << alpha_deg << " deg from "
            << sweeps.size() << " sweeps (" << rejected.size() << " rejected), "
            << result.iterations << " LM iterations, F_cost " << std::setprecision(4)
            << result.final_cost << ", " << result.stop_reason
            << (result.converged ? "" : " (NOT converged)") << "\n"
            << "  mean E_atti per sweep: " << e_before << " as assembled -> " << e_after
            << " with the calibrated alpha\n";
  if (alpha_true_rad) {
    std::cerr << std::setprecision(8) << "  ground truth alpha " << *alpha_true_rad * kRadToDeg
              << " deg: error " << std::setprecision(3) << (alpha_deg - *alpha_true_rad * kRadToDeg)
              << " deg\n";
  }
  std::cerr << std::fixed << std::setprecision(2) << "  time: sweep assembly " << read_s
            << " s, wall extraction " << walls_s << " s, LM " << std::setprecision(3) << lm_s * 1e3
            << " ms, total " << std::setprecision(2) << total_s << " s\n"
            << "  wrote " << o.out << "\n";
  std::cerr.unsetf(std::ios::floatfield);

  if (o.json) {
    nlohmann::json j;
    j["alpha_deg"] = alpha_deg;
    j["iterations"] = result.iterations;
    j["final_cost"] = result.final_cost;
    j["converged"] = result.converged;
    j["stop_reason"] = result.stop_reason;
    j["sweeps_used"] = sweeps.size();
    j["sweeps_rejected"] = rejected;
    j["log_errors"] = log_errors;
    j["e_atti_mean_before"] = e_before;
    j["e_atti_mean_after"] = e_after;
    nlohmann::json history = nlohmann::json::array();
    for (const auto& h : result.history) {
      history.push_back(
          {{"k", h.k}, {"alpha_deg", h.alpha_rad * kRadToDeg}, {"cost", h.cost}, {"mu", h.mu}});
    }
    j["history"] = history;
    if (alpha_true_rad) {
      j["alpha_true_deg"] = *alpha_true_rad * kRadToDeg;
      j["alpha_error_deg"] = alpha_deg - *alpha_true_rad * kRadToDeg;
    }
    j["timing_s"] = {
        {"sweep_assembly", read_s}, {"wall_extraction", walls_s}, {"lm", lm_s}, {"total", total_s}};
    j["out"] = o.out;
    std::cout << std::setprecision(12) << j.dump(2) << "\n";
  }
  return 0;
}


struct MountingOptions {
  std::string log, rig, out;
  std::vector<std::string> sets;
  bool json = false;
  std::string track = "ekf";  // ekf | wheels | truth
  bool time_offset = false;
  bool track_drift = false;  // also estimate the track's slow position drift (ours)
  bool no_paper = false;  // skip the paper's method (else reported beside ours)
  double min_pass_gap_s = MountingCalibrationOptions{}.min_pass_gap_s;
};

int runMounting(const MountingOptions& o) {
  using clock = std::chrono::steady_clock;
  const auto t_start = clock::now();
  MobileLidarConfig rig;
  try {
    rig = requireKind<MobileLidarConfig>(loadRig(o.rig, o.sets), "calib mounting");
  } catch (const std::exception& e) {
    std::cerr << "calib mounting: config error: " << e.what() << "\n";
    return 2;
  }
  if (!std::filesystem::is_regular_file(o.log)) {
    std::cerr << "calib mounting: log '" << o.log << "' does not exist or is not a file\n";
    return 2;
  }
  const std::filesystem::path out_dir = std::filesystem::absolute(o.out).parent_path();
  if (!std::filesystem::is_directory(out_dir)) {
    std::cerr << "calib mounting: output directory '" << out_dir.string() << "' does not exist\n";
    return 2;
  }
  MobileLog log;
  try {
    log = loadMobileLog(o.log, rig);
  } catch (const std::exception& e) {
    std::cerr << "calib mounting: cannot read log '" << o.log << "': " << e.what() << "\n";
    return 2;
  }
  if (log.log_error) {
    std::cerr << "calib mounting: " << o.log << ": " << log.error << " (the data before it is used)\n";
  }
  const PoseTrack* track = o.track == "wheels" ? &log.wheels : o.track == "truth" ? &log.truth : &log.ekf;
  if (o.track == "truth" && log.truth.size() == 0) {
    std::cerr << "calib mounting: --track truth: the log has no TRUTH_POSE (not simulated)\n";
    return 2;
  }
  const double load_s = seconds(clock::now() - t_start);
  std::cerr << "calib mounting: " << log.scans.size() << " scans, " << track->size() << " " << o.track
            << " poses from " << o.log << "\n";

  const LidarMounting initial = rig.mounting.toMounting();
  MountingCalibrationOptions options;
  options.min_pass_gap_s = o.min_pass_gap_s;
  options.estimate_time_offset = o.time_offset;
  options.estimate_track_drift = o.track_drift;
  options.method = MountingMethod::kPointToPlane;
  const auto t_ours = clock::now();
  const MountingCalibrationResult ours = calibrateMounting(log.scans, *track, initial, options);
  const double ours_s = seconds(clock::now() - t_ours);
  std::optional<MountingCalibrationResult> paper;
  double paper_s = 0;
  if (!o.no_paper) {
    options.method = MountingMethod::kPaperPoints;
    options.estimate_time_offset = false;
    const auto t_paper = clock::now();
    paper = calibrateMounting(log.scans, *track, initial, options);
    paper_s = seconds(clock::now() - t_paper);
  }

  std::optional<LidarMounting> truth;
  if (log.truth_mounting) truth = trueMounting(*log.truth_mounting);
  const auto report = [&](const MountingCalibrationResult& r, double secs) {
    std::cerr << "  " << mountingMethodName(r.method) << ": ";
    if (!r.ok) {
      std::cerr << "FAILED: " << r.reason << "\n";
      return;
    }
    std::cerr << std::setprecision(6) << "gamma " << r.gamma_rad << ", beta " << r.beta_rad << ", alpha "
              << r.alpha_rad << " rad";
    if (o.time_offset && r.method == MountingMethod::kPointToPlane) {
      std::cerr << ", time offset " << r.time_offset_s * 1e3 << " ms";
    }
    if (o.track_drift && r.method == MountingMethod::kPointToPlane) {
      std::cerr << ", track drift (" << r.drift_x_m_s * 1e3 << ", " << r.drift_y_m_s * 1e3 << ") mm/s";
    }
    std::cerr << "; residual RMS " << std::setprecision(4) << r.residual_before_m * 1e3 << " -> "
              << r.residual_after_m * 1e3 << " mm over " << r.correspondences << " correspondences, "
              << r.iterations << " iterations, " << std::setprecision(3) << secs << " s\n";
    if (truth) {
      std::cerr << std::setprecision(3) << "    error vs truth: gamma "
                << (r.gamma_rad - truth->gamma_rad) * 1e3 << ", beta "
                << (r.beta_rad - truth->beta_rad) * 1e3 << ", alpha "
                << (r.alpha_rad - truth->alpha_rad) * 1e3 << " mrad\n";
    }
  };
  report(ours, ours_s);
  if (paper) report(*paper, paper_s);
  const bool offset_at_bound =
      o.time_offset && ours.ok && std::abs(ours.time_offset_s) >= 0.99 * options.max_time_offset_s;
  if (offset_at_bound) {
    std::cerr << "calib mounting: warning: the time offset ran to its bound (+-" << options.max_time_offset_s
              << " s): the drive does not observe it (a steady circle only turns the whole cloud); "
                 "calibrate without --time-offset\n";
  }

  nlohmann::json j = nlohmann::json::parse(mountingResultJsonText(ours, truth));
  j["time_s"] = ours_s;
  j["track"] = o.track;
  if (o.time_offset) j["time_offset_at_bound"] = offset_at_bound;
  j["log"] = o.log;
  j["scans"] = log.scans.size();
  if (log.log_error) j["log_error"] = log.error;
  if (paper) {
    j["paper"] = nlohmann::json::parse(mountingResultJsonText(*paper, truth));
    j["paper"]["time_s"] = paper_s;
  }
  if (truth) {
    j["truth"] = {{"gamma_rad", truth->gamma_rad}, {"beta_rad", truth->beta_rad}, {"alpha_rad", truth->alpha_rad}};
  }

  if (!ours.ok) {
    std::cerr << "calib mounting: nothing calibrated: " << ours.reason << "\n";
    if (o.json) std::cout << std::setprecision(12) << j.dump(2) << "\n";
    return 1;
  }
  MountingCalibration c;
  c.gamma_rad = ours.gamma_rad;
  c.beta_rad = ours.beta_rad;
  c.alpha_rad = ours.alpha_rad;
  c.source["tool"] = "sweepmap calib mounting";
  c.source["date"] = utcNow();
  c.source["method"] = mountingMethodName(ours.method);
  c.source["track"] = o.track;
  std::ostringstream text;
  text << std::setprecision(6) << ours.residual_before_m << " -> " << ours.residual_after_m;
  c.source["residual_rms_m"] = text.str();
  c.source["correspondences"] = std::to_string(ours.correspondences);
  if (o.time_offset) {
    std::ostringstream dt;
    dt << std::setprecision(6) << ours.time_offset_s;
    c.source["time_offset_s"] = dt.str();
  }
  c.logs = {o.log};
  try {
    writeMountingCalibration(o.out, c);
  } catch (const std::exception& e) {
    std::cerr << "calib mounting: " << e.what() << "\n";
    return 2;
  }
  const double total_s = seconds(clock::now() - t_start);
  std::cerr << std::fixed << std::setprecision(2) << "  time: log " << load_s << " s, ours " << ours_s
            << " s, paper " << paper_s << " s, total " << total_s << " s\n  wrote " << o.out << "\n";
  std::cerr.unsetf(std::ios::floatfield);
  if (o.json) {
    j["timing_s"] = {{"log", load_s}, {"point_to_plane", ours_s}, {"paper_points", paper_s}, {"total", total_s}};
    j["out"] = o.out;
    std::cout << std::setprecision(12) << j.dump(2) << "\n";
  }
  return 0;
}

}  // namespace

Runner addCalibCommand(CLI::App& app) {
  auto* calib = app.add_subcommand(
      "calib",
      "Calibrate the rig from its own logs and write the result as a calibration file the rig "
      "file points to. Subcommands by the rig's kind: plate-angle (rotating_lidar), mounting (mobile_lidar)");
  calib->require_subcommand(1);

  auto* plate = calib->add_subcommand(
      "plate-angle",
      "rotating_lidar rigs (rig A): calibrate the triangular plate's installation angle alpha (Yuan 2021 section 4.2, "
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
      "Exit status: 0 calibrated; 1 no usable sweep; 2 bad rig, log or output path.\n"
      "Example: sweepmap calib plate-angle --logs room.lcmlog --rig rig_a "
      "--out config/plate_calibration.yaml");
  auto o = std::make_shared<PlateAngleOptions>();
  plate->add_option("--logs", o->logs, "LCM logs of the room (sweepmap sim, lcm-logger)")
      ->required()
      ->expected(1, -1);
  plate->add_option("--rig", o->rig, "rig file or name (rotating_lidar) the logs were recorded with")->required();
  plate->add_option("--out", o->out, "calibration file to write (YAML, atomically)")->required();
  plate->add_flag("--json", o->json, "print the result as JSON on stdout");
  plate->add_option("--set", o->sets, "override a rig config key: key=value (repeatable)");
  plate->add_option("--voxel", o->voxel_m, "voxel size [m] of the wall extraction's downsampling")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);

  auto* mount = calib->add_subcommand(
      "mounting",
      "mobile_lidar rigs (rig B): calibrate the lidar's 3-axis mounting error (gamma about body x, beta about y, "
      "alpha about z; Miao 2022 section 4.2) from a drive that sees the same surfaces twice "
      "(the circle of `sweepmap sim --rig rig_b`, a calibration target in view)");
  mount->footer(
      "The log's wheel and IMU messages are replayed through the odometry node (EKF) for the "
      "track; every lidar ray is placed in the world with the pose at its own time. On a circle a "
      "place is seen by one half of the scan and, half a turn later, by the other: the two passes.\n\n"
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
      "time_offset_s, residual_before_m, residual_after_m (RMS), correspondences, method, the "
      "paper's result under \"paper\" and, for simulated logs, the truth and error_mrad.\n\n"
      "Exit status: 0 calibrated; 1 not calibrated (too little data, no overlap); 2 bad rig, log "
      "or output path.\n"
      "Example: sweepmap sim --rig rig_b --set sim.duration_s=120 --out circle.lcmlog && "
      "sweepmap calib mounting --log circle.lcmlog --rig rig_b --out "
      "config/mounting_calibration.yaml");
  auto m = std::make_shared<MountingOptions>();
  mount->add_option("--log", m->log, "LCM log of the drive (sweepmap sim, lcm-logger)")->required();
  mount->add_option("--rig", m->rig, "rig file or name (mobile_lidar) the log was recorded with")->required();
  mount->add_option("--out", m->out, "calibration file to write (YAML, atomically)")->required();
  mount->add_flag("--json", m->json, "print the result as JSON on stdout");
  mount->add_option("--set", m->sets, "override a rig config key: key=value (repeatable)");
  mount->add_option("--track", m->track, "poses: ekf (ODOMETRY_POSE replayed), wheels, truth (simulated logs)")
      ->capture_default_str()
      ->check(CLI::IsMember({"ekf", "wheels", "truth"}));
  mount->add_flag("--time-offset", m->time_offset, "also estimate the lidar-to-odometry time offset (ours)");
  mount->add_flag("--track-drift", m->track_drift,
                  "also estimate a slow drift (world velocity) of the track's position (ours; odometry tracks)");
  mount->add_flag("--no-paper", m->no_paper, "skip the paper's method");
  mount->add_option("--min-pass-gap", m->min_pass_gap_s,
                    "seconds between two observations of a place for them to be two passes")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  return [plate, o, mount, m]() {
    if (plate->parsed()) return runPlateAngle(*o);
    if (mount->parsed()) return runMounting(*m);
    return 2;
  };
}

}  // namespace sweepmap
