// `sweepmap calib plate-angle`'s workflow in named steps: check the inputs, read the logs'
// sweeps and their walls, fit alpha (Algorithm A1), write the calibration file, report.
#include "tools/offline/calibrate_plate.hpp"

#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "calib/plate_angle.hpp"
#include "calib/rig_calibration.hpp"
#include "core/angles.hpp"
#include "core/calibration_file.hpp"
#include "core/event_log.hpp"
#include "core/exit_codes.hpp"
#include "tools/offline/calibrate_common.hpp"
#include "tools/offline/log_sweeps.hpp"

namespace sweepmap {
namespace {

using calib_workflow::kCalibPlateAngle;

using calib_workflow::Clock;
using calib_workflow::seconds;

struct RejectedSweep {
  std::string log;
  int64_t id = 0;
  std::string reason;
};

struct LogFailure {
  std::string log, error;
};

// What the logs gave: the wall normals of every usable sweep, and why the others were not.
struct LogSweeps {
  std::vector<SweepNormals> sweeps;
  std::vector<RejectedSweep> rejected;
  std::vector<LogFailure> log_errors;        // corrupt tails (the sweeps before them are used)
  std::optional<double> alpha_true_rad;      // the first truth a log carries (simulated logs)
  int seen = 0;                              // sweeps assembled
  double walls_s = 0, read_s = 0;            // wall extraction; the rest of reading the logs
  std::vector<double> wall_cell_medians_mm;  // the walls' flatness (calib/rig_calibration.hpp)
};

// Walls that bend more than noise does: another parameter of the rig is off.
constexpr double kWallCellLimitMm = 2.0;  // 0.7 mm on the paper model, 3.5 with a 0.3 deg tilt

// alpha fitted over the sweeps' normals.
struct AlphaFit {
  LmResult lm;
  double lm_s = 0;
  double e_before = 0, e_after = 0;  // mean E_atti per sweep: as assembled, with lm.alpha_rad
  double alpha_deg = 0;
};

// Check the inputs: the rig (rotating_lidar), the logs and the output folder; false after
// saying on stderr what is wrong.
bool checkInputs(const PlateAngleCalibRequest& o, RotatingLidarConfig* rig) {
  if (!calib_workflow::loadRigOfKind(o.rig, o.sets, kCalibPlateAngle, rig)) return false;
  for (const auto& log : o.logs) {
    if (!calib_workflow::logFileExists(log, kCalibPlateAngle)) return false;
  }
  return calib_workflow::outputDirExists(o.out, kCalibPlateAngle);
}

// One assembled sweep: the normals of its four walls into in->sweeps, or why not into
// in->rejected, each with a line on stderr. Returns the seconds the wall extraction took.
double takeSweep(const std::string& log, const AssembledSweep& s,
                 const WallExtractionOptions& wall_options, LogSweeps* in) {
  ++in->seen;
  const auto reject = [&](const std::string& reason) {
    in->rejected.push_back({log, s.window.sweep_id, reason});
    std::cerr << "  " << log << " sweep " << s.window.sweep_id << ": rejected: " << reason << "\n";
  };
  if (!s.corrected) {
    reject("not corrected: " + s.reason);
    return 0.0;
  }
  const auto t0 = Clock::now();
  const WallExtraction e = extractWalls(s.points, wall_options);
  const double walls_s = seconds(Clock::now() - t0);
  if (e.walls.empty()) {
    reject("walls: " + e.reason);
    return walls_s;
  }
  SweepNormals n;
  n.alpha_used_rad = s.alpha_rad;
  for (const auto& w : e.walls) {
    n.normals.push_back(w.normal);
    const auto m = planeCellMediansMm(s.points, w.inlier_indices, w.normal, w.offset, 0.5, 100);
    in->wall_cell_medians_mm.insert(in->wall_cell_medians_mm.end(), m.begin(), m.end());
  }
  std::cerr << "  " << log << " sweep " << s.window.sweep_id << ": 4 walls, E_atti "
            << std::setprecision(4) << attitudeError(n) << " at alpha " << std::setprecision(8)
            << s.alpha_rad * kRadToDeg << " deg\n";
  in->sweeps.push_back(std::move(n));
  return walls_s;
}

// Read one log: every sweep the assembler builds from it through takeSweep. False (after
// saying so) if the log cannot be opened; a corrupt tail is noted and what came before used.
bool readLog(const std::string& log, const RotatingLidarConfig& rig,
             const WallExtractionOptions& wall_options, LogSweeps* in) {
  const auto t_log = Clock::now();
  double walls_this_log_s = 0;
  LogReadResult r;
  try {
    r = forEachSweep(log, rig, [&](const AssembledSweep& s, const SweepTruth&) {
      walls_this_log_s += takeSweep(log, s, wall_options, in);
    });
  } catch (const LogError& e) {
    std::cerr << kCalibPlateAngle << ": cannot read log '" << log << "': " << e.what() << "\n";
    return false;
  }
  in->walls_s += walls_this_log_s;
  in->read_s += seconds(Clock::now() - t_log) - walls_this_log_s;
  if (r.log_error) {
    std::cerr << kCalibPlateAngle << ": " << r.error << " (the sweeps before it are used)\n";
    in->log_errors.push_back({log, r.error});
  }
  if (r.alpha_true_rad && !in->alpha_true_rad) in->alpha_true_rad = r.alpha_true_rad;
  return true;
}

nlohmann::json rejectedJson(const std::vector<RejectedSweep>& rejected) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& r : rejected) j.push_back({{"log", r.log}, {"id", r.id}, {"reason", r.reason}});
  return j;
}

nlohmann::json logErrorsJson(const std::vector<LogFailure>& log_errors) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& e : log_errors) j.push_back({{"log", e.log}, {"error", e.error}});
  return j;
}

// Report that no sweep was usable; the exit status 1.
int reportNothingCalibrated(const PlateAngleCalibRequest& o, const LogSweeps& in) {
  std::cerr << kCalibPlateAngle << ": no usable sweep (" << in.seen << " seen, "
            << in.rejected.size() << " rejected) in " << o.logs.size()
            << " log(s): nothing calibrated\n";
  if (o.json) {
    std::cout << nlohmann::json{{"sweeps_used", 0},
                                {"sweeps_rejected", rejectedJson(in.rejected)},
                                {"log_errors", logErrorsJson(in.log_errors)}}
                     .dump(2)
              << "\n";
  }
  return 1;
}

// Run the method: Algorithm A1 over the sweeps' wall normals, and the mean attitude error
// before and after.
AlphaFit fitAlpha(const std::vector<SweepNormals>& sweeps) {
  AlphaFit f;
  const auto t_lm = Clock::now();
  LmOptions lm;  // Algorithm A1's parameters; alpha_0 = 30 deg as in the paper
  f.lm = calibratePlateAngle(sweeps, lm);
  f.lm_s = seconds(Clock::now() - t_lm);
  for (const auto& s : sweeps) {
    f.e_before += attitudeError(s);
    f.e_after += fCost(s, f.lm.alpha_rad);
  }
  f.e_before /= sweeps.size();
  f.e_after /= sweeps.size();
  f.alpha_deg = f.lm.alpha_rad * kRadToDeg;
  return f;
}

// Write the calibration file: alpha and its provenance (throws if it cannot).
void writeCalibration(const PlateAngleCalibRequest& o, const LogSweeps& in, const AlphaFit& f) {
  PlateCalibration c;
  c.alpha_deg = f.alpha_deg;
  c.source["tool"] = "sweepmap calib plate-angle";
  c.source["sweeps_used"] = std::to_string(in.sweeps.size());
  std::ostringstream cost;
  cost << std::setprecision(6) << f.lm.final_cost;
  c.source["final_cost"] = cost.str();
  c.source["iterations"] = std::to_string(f.lm.iterations);
  c.source["converged"] = f.lm.converged ? "true" : "false";
  c.logs = o.logs;
  writePlateCalibration(o.out, c);
}

// Report for humans on stderr: the result, its error against the truth, the timing.
void reportHuman(const PlateAngleCalibRequest& o, const LogSweeps& in, const AlphaFit& f,
                 double total_s) {
  const LmResult& result = f.lm;
  std::cerr << std::setprecision(8) << kCalibPlateAngle << ": alpha = " << f.alpha_deg
            << " deg from " << in.sweeps.size() << " sweeps (" << in.rejected.size()
            << " rejected), " << result.iterations << " LM iterations, F_cost "
            << std::setprecision(4) << result.final_cost << ", " << result.stop_reason
            << (result.converged ? "" : " (NOT converged)") << "\n"
            << "  mean E_atti per sweep: " << f.e_before << " as assembled -> " << f.e_after
            << " with the calibrated alpha\n";
  if (in.alpha_true_rad) {
    std::cerr << std::setprecision(8) << "  ground truth alpha " << *in.alpha_true_rad * kRadToDeg
              << " deg: error " << std::setprecision(3)
              << (f.alpha_deg - *in.alpha_true_rad * kRadToDeg) << " deg\n";
  }
  const std::string w = wallsDisagreeWarning(rmsOf(in.wall_cell_medians_mm), kWallCellLimitMm);
  if (!w.empty()) std::cerr << "  warning: " << w << "\n";
  std::cerr << std::fixed << std::setprecision(2) << "  time: sweep assembly " << in.read_s
            << " s, wall extraction " << in.walls_s << " s, LM " << std::setprecision(3)
            << f.lm_s * 1e3 << " ms, total " << std::setprecision(2) << total_s << " s\n"
            << "  wrote " << o.out << "\n";
  std::cerr.unsetf(std::ios::floatfield);
}

// Report as JSON on stdout (--json).
void reportJson(const PlateAngleCalibRequest& o, const LogSweeps& in, const AlphaFit& f,
                double total_s) {
  const LmResult& result = f.lm;
  nlohmann::json j;
  j["alpha_deg"] = f.alpha_deg;
  j["iterations"] = result.iterations;
  j["final_cost"] = result.final_cost;
  j["converged"] = result.converged;
  j["stop_reason"] = result.stop_reason;
  j["sweeps_used"] = in.sweeps.size();
  j["sweeps_rejected"] = rejectedJson(in.rejected);
  j["log_errors"] = logErrorsJson(in.log_errors);
  j["e_atti_mean_before"] = f.e_before;
  j["e_atti_mean_after"] = f.e_after;
  nlohmann::json history = nlohmann::json::array();
  for (const auto& h : result.history) {
    history.push_back(
        {{"k", h.k}, {"alpha_deg", h.alpha_rad * kRadToDeg}, {"cost", h.cost}, {"mu", h.mu}});
  }
  j["history"] = history;
  if (in.alpha_true_rad) {
    j["alpha_true_deg"] = *in.alpha_true_rad * kRadToDeg;
    j["alpha_error_deg"] = f.alpha_deg - *in.alpha_true_rad * kRadToDeg;
  }
  j["timing_s"] = {{"sweep_assembly", in.read_s},
                   {"wall_extraction", in.walls_s},
                   {"lm", f.lm_s},
                   {"total", total_s}};
  j["out"] = o.out;
  j["wall_cell_rms_mm"] = rmsOf(in.wall_cell_medians_mm);
  const std::string w = wallsDisagreeWarning(rmsOf(in.wall_cell_medians_mm), kWallCellLimitMm);
  j["warnings"] = w.empty() ? nlohmann::json::array() : nlohmann::json::array({w});
  std::cout << std::setprecision(12) << j.dump(2) << "\n";
}

}  // namespace

int calibratePlateAngleFromLogs(const PlateAngleCalibRequest& o) {
  const auto t_start = Clock::now();
  RotatingLidarConfig rig;
  if (!checkInputs(o, &rig)) return kExitUsage;
  WallExtractionOptions wall_options;
  wall_options.voxel_m = o.voxel_m;
  LogSweeps in;
  for (const auto& log : o.logs) {
    if (!readLog(log, rig, wall_options, &in)) return kExitBadInput;
  }
  if (in.sweeps.empty()) return reportNothingCalibrated(o, in);
  const AlphaFit f = fitAlpha(in.sweeps);
  try {
    writeCalibration(o, in, f);
  } catch (const std::exception& e) {
    std::cerr << "calib plate-angle: " << e.what() << "\n";
    return kExitDeviceIo;  // the file could not be written
  }
  const double total_s = seconds(Clock::now() - t_start);
  reportHuman(o, in, f, total_s);
  if (o.json) reportJson(o, in, f, total_s);
  return 0;
}

}  // namespace sweepmap
