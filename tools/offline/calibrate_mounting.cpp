// `sweepmap calib mounting`'s workflow in named steps: check the inputs, read the log
// (odometry replayed), run both methods, write the calibration file, report.
#include "tools/offline/calibrate_mounting.hpp"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "calib/wheel_gyro_calibration.hpp"
#include "core/calibration_file.hpp"
#include "core/exit_codes.hpp"
#include "core/progress.hpp"
#include "tools/offline/calibrate_common.hpp"
#include "tools/offline/mobile_log.hpp"

namespace sweepmap {
namespace {

using calib_workflow::kCalibMounting;

using calib_workflow::Clock;
using calib_workflow::seconds;

// Both methods' results and how long each took.
struct MethodRuns {
  MountingCalibrationResult ours;  // point-to-plane: the result written
  double ours_s = 0;
  std::optional<MountingCalibrationResult> paper;  // the paper's points, unless no_paper
  double paper_s = 0;
  double max_time_offset_s = 0;  // the bound of ours' time offset
};

// Check the inputs: the rig (mobile_lidar), the log and the output folder; false after
// saying on stderr what is wrong.
bool checkInputs(const MountingCalibRequest& o, MobileLidarConfig* rig) {
  if (!calib_workflow::loadRigOfKind(o.rig, o.sets, kCalibMounting, rig)) return false;
  if (!calib_workflow::logFileExists(o.log, kCalibMounting)) return false;
  return calib_workflow::outputDirExists(o.out, kCalibMounting);
}

const PoseTrack& chosenTrack(const MobileLog& log, const std::string& track) {
  return track == "wheels" ? log.wheels : track == "truth" ? log.truth : log.ekf;
}

// Read the log: its scans and the odometry replayed over it. False (after saying so) if it
// cannot be read or lacks the track asked for; a corrupt tail is noted and what came
// before used.
bool readLog(const MountingCalibRequest& o, const MobileLidarConfig& rig, MobileLog* log) {
  try {
    *log = loadMobileLog(o.log, rig);
  } catch (const std::exception& e) {
    std::cerr << kCalibMounting << ": cannot read log '" << o.log << "': " << e.what() << "\n";
    return false;
  }
  if (log->log_error) {
    std::cerr << kCalibMounting << ": " << o.log << ": " << log->error
              << " (the data before it is used)\n";
  }
  if (o.track == "truth" && log->truth.size() == 0) {
    std::cerr << kCalibMounting << ": --track truth: the log has no TRUTH_POSE (not simulated)\n";
    return false;
  }
  return true;
}

// Run the methods from the rig's mounting: ours, then the paper's (without a time offset).
MethodRuns runMethods(const MountingCalibRequest& o, const MobileLidarConfig& rig,
                      const MobileLog& log, const PoseTrack& track, Progress& progress) {
  MethodRuns runs;
  const LidarMounting initial = rig.mounting.toMounting();
  MountingCalibrationOptions options;
  options.min_pass_gap_s = o.min_pass_gap_s;
  options.estimate_time_offset = o.time_offset;
  options.estimate_track_drift = o.track_drift;
  options.method = MountingMethod::kPointToPlane;
  runs.max_time_offset_s = options.max_time_offset_s;
  options.progress = [&progress](double f) { progress.update(f); };
  const auto t_ours = Clock::now();
  progress.stage("ours (point to plane)");
  runs.ours = calibrateMounting(log.scans, track, initial, options);
  runs.ours_s = seconds(Clock::now() - t_ours);
  if (!o.no_paper) {
    options.method = MountingMethod::kPaperPoints;
    options.estimate_time_offset = false;
    const auto t_paper = Clock::now();
    progress.stage("the paper's (edge points)");
    runs.paper = calibrateMounting(log.scans, track, initial, options);
    runs.paper_s = seconds(Clock::now() - t_paper);
  }
  return runs;
}

// Report one method's result for humans on stderr, with its error against the truth.
void reportMethod(const MountingCalibRequest& o, const MountingCalibrationResult& r, double secs,
                  const std::optional<LidarMounting>& truth) {
  std::cerr << "  " << mountingMethodName(r.method) << ": ";
  if (!r.ok) {
    std::cerr << "FAILED: " << r.reason << "\n";
    return;
  }
  std::cerr << std::setprecision(6) << "gamma " << r.gamma_rad << ", beta " << r.beta_rad
            << ", alpha " << r.alpha_rad << " rad";
  if (o.time_offset && r.method == MountingMethod::kPointToPlane) {
    std::cerr << ", time offset " << r.time_offset_s * 1e3 << " ms";
  }
  if (o.track_drift && r.method == MountingMethod::kPointToPlane) {
    std::cerr << ", track drift (" << r.drift_x_m_s * 1e3 << ", " << r.drift_y_m_s * 1e3
              << ") mm/s";
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
}

// Whether ours' time offset ran to its bound (then a warning on stderr).
bool timeOffsetAtBound(const MountingCalibRequest& o, const MethodRuns& runs) {
  const bool at_bound = o.time_offset && runs.ours.ok &&
                        std::abs(runs.ours.time_offset_s) >= 0.99 * runs.max_time_offset_s;
  if (at_bound) {
    std::cerr << kCalibMounting << ": warning: the time offset ran to its bound (+-"
              << runs.max_time_offset_s
              << " s): the drive does not observe it (a steady circle only turns the whole "
                 "cloud); calibrate without --time-offset\n";
  }
  return at_bound;
}

// The other parameters the drive shows off, as warnings: each wheel's radius over the track
// against the gyro (calib rig's first step; the turn rates they give disagree with the gyro's
// when a radius or the track is off, and the track the mounting was fitted on bends with
// them). Said on stderr too.
std::vector<std::string> othersOff(const MountingCalibRequest& o, const MobileLidarConfig& rig) {
  std::vector<std::string> warnings;
  if (o.track == "truth") return warnings;  // the true track: the wheels do not enter
  const OdometryReadings readings = loadOdometryReadings(o.log);
  WheelGyroOptions options;
  options.ticks_per_revolution = rig.odometry.ticks_per_revolution;
  const WheelGyroResult wg = calibrateWheelsAgainstGyro(readings.wheels, readings.gyro, options);
  if (!wg.ok) {
    warnings.push_back("this drive cannot check the wheels against the gyro (" + wg.reason +
                       "), so the mounting assumes the rig file's wheel radii and track; drive "
                       "the figure-eight `sweepmap calib plan` asks for, or run "
                       "`sweepmap calib rig` on it, to check them");
    for (const auto& text : warnings) std::cerr << kCalibMounting << ": warning: " << text << "\n";
    return warnings;
  }
  const double r_right = rig.odometry.rightWheelRadius();
  const double nominal[2] = {rig.odometry.wheel_radius_m / rig.odometry.ekf.wheel_distance_m,
                             r_right / rig.odometry.ekf.wheel_distance_m};
  std::ostringstream w;
  w << std::fixed << std::setprecision(2);
  bool off = false;
  for (int k = 0; k < 2; ++k) {
    const double sigma = std::sqrt(std::max(0.0, wg.covariance(k, k)));
    const double d = wg.x(k) - nominal[k];
    if (!(std::abs(d) > 3.0 * sigma)) continue;
    w << (off ? ", " : "") << (k ? "right" : "left") << " " << 100.0 * d / nominal[k] << " +- "
      << 100.0 * sigma / nominal[k] << " %";
    off = true;
  }
  if (off) {
    warnings.push_back(
        "the wheels disagree with the gyro: radius over track off the rig file's by " + w.str() +
        " (the turn rates they give are not the gyro's), so the odometry track this fit used "
        "is biased; run `sweepmap calib rig`, which calibrates the wheels with the mounting");
  }
  for (const auto& text : warnings) std::cerr << kCalibMounting << ": warning: " << text << "\n";
  return warnings;
}

// The JSON report without its timing: ours at the top, the paper's under "paper", the truth.
nlohmann::json resultJson(const MountingCalibRequest& o, const MobileLog& log,
                          const MethodRuns& runs, const std::optional<LidarMounting>& truth,
                          bool offset_at_bound) {
  nlohmann::json j = nlohmann::json::parse(mountingResultJsonText(runs.ours, truth));
  j["time_s"] = runs.ours_s;
  j["track"] = o.track;
  if (o.time_offset) j["time_offset_at_bound"] = offset_at_bound;
  j["log"] = o.log;
  j["scans"] = log.scans.size();
  if (log.log_error) j["log_error"] = log.error;
  if (runs.paper) {
    j["paper"] = nlohmann::json::parse(mountingResultJsonText(*runs.paper, truth));
    j["paper"]["time_s"] = runs.paper_s;
  }
  if (truth) {
    j["truth"] = {{"gamma_rad", truth->gamma_rad},
                  {"beta_rad", truth->beta_rad},
                  {"alpha_rad", truth->alpha_rad}};
  }
  return j;
}

// Write the calibration file: ours and its provenance. False after saying why it cannot.
bool writeCalibration(const MountingCalibRequest& o, const MountingCalibrationResult& ours) {
  MountingCalibration c;
  c.gamma_rad = ours.gamma_rad;
  c.beta_rad = ours.beta_rad;
  c.alpha_rad = ours.alpha_rad;
  c.source["tool"] = "sweepmap calib mounting";
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
    std::cerr << kCalibMounting << ": " << e.what() << "\n";
    return false;
  }
  return true;
}

}  // namespace

int calibrateMountingFromLog(const MountingCalibRequest& o) {
  const auto t_start = Clock::now();
  MobileLidarConfig rig;
  if (!checkInputs(o, &rig)) return kExitUsage;
  ProgressOptions po;
  po.enabled = !o.json;
  Progress progress(kCalibMounting, po);
  MethodRuns runs;
  MobileLog log;
  {
    ProgressTicker ticker(progress);  // the stages are single long calls
    progress.stage("reading the log");
    if (!readLog(o, rig, &log)) return kExitBadInput;
    progress.stage("");
    runs = runMethods(o, rig, log, chosenTrack(log, o.track), progress);
  }
  progress.finish();
  const PoseTrack& track = chosenTrack(log, o.track);
  const double load_s = seconds(Clock::now() - t_start) - runs.ours_s - runs.paper_s;
  std::cerr << kCalibMounting << ": " << log.scans.size() << " scans, " << track.size() << " "
            << o.track << " poses from " << o.log << "\n";

  std::optional<LidarMounting> truth;
  if (log.truth_mounting) truth = trueMounting(*log.truth_mounting);
  reportMethod(o, runs.ours, runs.ours_s, truth);
  if (runs.paper) reportMethod(o, *runs.paper, runs.paper_s, truth);
  nlohmann::json j = resultJson(o, log, runs, truth, timeOffsetAtBound(o, runs));
  j["warnings"] = othersOff(o, rig);

  if (!runs.ours.ok) {
    std::cerr << kCalibMounting << ": nothing calibrated: " << runs.ours.reason << "\n";
    if (o.json) std::cout << std::setprecision(12) << j.dump(2) << "\n";
    return 1;
  }
  if (!writeCalibration(o, runs.ours)) return kExitDeviceIo;
  const double total_s = seconds(Clock::now() - t_start);
  std::cerr << std::fixed << std::setprecision(2) << "  time: log " << load_s << " s, ours "
            << runs.ours_s << " s, paper " << runs.paper_s << " s, total " << total_s
            << " s\n  wrote " << o.out << "\n";
  std::cerr.unsetf(std::ios::floatfield);
  if (o.json) {
    j["timing_s"] = {{"log", load_s},
                     {"point_to_plane", runs.ours_s},
                     {"paper_points", runs.paper_s},
                     {"total", total_s}};
    j["out"] = o.out;
    std::cout << std::setprecision(12) << j.dump(2) << "\n";
  }
  return 0;
}

}  // namespace sweepmap
