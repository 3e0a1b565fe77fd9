// The two ways to evaluate rig A: existing logs (evalRotatingLogs) and the simulated paper
// experiment (runPaperExperiment, in steps). The measures are in rotating_metrics, the
// report and its figures in rotating_report and rotating_figures.
#include "tools/eval/eval_rotating.hpp"

#include <filesystem>
#include <iostream>
#include <map>
#include <stdexcept>

#include "core/angles.hpp"
#include "core/calibration_file.hpp"
#include "core/event_log.hpp"
#include "tools/eval/common.hpp"
#include "tools/eval/rotating_metrics.hpp"
#include "tools/eval/rotating_report.hpp"
#include "tools/offline/runs.hpp"
#include "tools/offline/simulation.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;
using eval::fixed;
using eval::Group;
using eval::Method;
using eval::MethodRigs;
using eval::ReportInput;
using eval::Stopwatch;
using eval::SweepRecord;

void progressLine(const EvalSettings& s, const std::string& line) {
  eval::progressLine(s.progress, line);
}

std::optional<double> firstAlphaTruth(const std::vector<eval::LogStatus>& logs) {
  for (const auto& l : logs) {
    if (l.alpha_true_rad) return l.alpha_true_rad;
  }
  return std::nullopt;
}

std::vector<const SweepRecord*> mode7Records(const std::map<int, Group>& groups) {
  std::vector<const SweepRecord*> out;
  const auto it = groups.find(7);
  if (it == groups.end()) return out;
  for (const auto& r : it->second.sweeps) out.push_back(&r);
  return out;
}

// Writes the report and says where it is.
EvalRotatingResult finish(const fs::path& out, const ReportInput& in, const EvalSettings& s,
                          const Stopwatch& total) {
  Stopwatch report_watch;
  EvalRotatingResult r = eval::writeReport(out, in, s);
  progressLine(s, "report and figures: " + fixed(report_watch.seconds(), 1) + " s; total " +
                      fixed(total.seconds(), 1) + " s -> " + (out / "report.md").string());
  return r;
}

// --- the paper experiment, step by step --------------------------------------------------

// What the steps of the experiment share: the rig and scene they simulate, where they write,
// and the report input they fill.
struct PaperRun {
  const PaperExperimentOptions& o;
  RotatingLidarConfig rig;
  SceneConfig scene;
  fs::path out;
  ReportInput in;
};

PaperRun startPaperRun(const PaperExperimentOptions& o) {
  if (o.sweeps_per_mode < 1) throw std::runtime_error("--sweeps-per-mode must be at least 1");
  if (o.calib_sweeps < 1) throw std::runtime_error("--calib-sweeps must be at least 1");
  // The paper's settings where it defines them (its model has no tilted scan plane, no mirror
  // offset, a flat plate and no scene artefacts); the user's --set still wins.
  std::vector<std::string> overrides = SimRigConfig::paperSettings();
  overrides.insert(overrides.end(), o.overrides.begin(), o.overrides.end());
  const SimSetup setup = loadSimSetup(o.rig_path, o.scene_path, overrides);
  PaperRun run{o,
               requireKind<RotatingLidarConfig>(setup.rig, "this experiment"),
               setup.scene,
               fs::path(o.out_dir),
               {}};
  fs::create_directories(run.out / "logs");
  run.in.inputs.rig = o.rig_path;
  run.in.inputs.overrides = o.overrides;
  eval::ExperimentInputs& e = run.in.inputs.experiment.emplace();
  e.scene = o.scene_path;
  e.seed = o.seed;
  e.sweeps_per_mode = o.sweeps_per_mode;
  e.calib_sweeps = o.calib_sweeps;
  e.naive = o.naive;
  e.rig = run.rig;
  run.in.mapper = run.rig.mapper;
  return run;
}

// Simulates `sweeps` sweeps of `mode` into DIR/logs/`file`; returns the log's path.
std::string simulateLog(PaperRun& run, const std::string& file, int mode,
                        const std::string& sequence, int sweeps, uint64_t seed) {
  const EvalSettings& s = run.o.settings;
  Stopwatch w;
  SimOptions so;
  so.rig = run.rig;
  so.rig.motor.mode = mode;
  so.rig.motor.action_sequence = sequence;
  so.scene = run.scene;
  so.sweeps = sweeps;
  so.seed = seed;
  const std::string path = (run.out / "logs" / file).string();
  progressLine(s, "simulating " + file + ": mode " + std::to_string(mode) + ", " + sequence +
                      " sequence, " + std::to_string(sweeps) + " sweeps, seed " +
                      std::to_string(seed));
  EventLogWriter log(path);
  const SimResult r =
      simulate(so, [&](const Message& m) { log.write(m.utime, m.channel, m.data); });
  log.close();
  progressLine(s, "  " + std::to_string(r.sweeps_done) + " sweeps, " +
                      fixed(r.simulated_us / 1e6, 1) + " s simulated in " + fixed(w.seconds(), 1) +
                      " s");
  if (r.motor_fault || r.sweeps_done != sweeps) {
    std::cerr << "eval: " << file << ": only " << r.sweeps_done << " of " << sweeps
              << " sweeps simulated" << (r.motor_fault ? " (motor fault)" : "") << "\n";
  }
  run.in.inputs.experiment->seeds[file] = seed;
  run.in.timings_s["simulate_" + file] = roundTo(w.seconds(), 6);
  return path;
}

// 1. Alpha from the mode-7 calibration log, assembled with the rig's (nominal) alpha.
// Throws if the default method could not calibrate it.
void calibrateAlphaFromLog(PaperRun& run, const std::string& calib_log) {
  ReportInput& in = run.in;
  std::map<int, Group> calib_groups;
  {
    Stopwatch w;
    in.logs.push_back(eval::evaluateLog(calib_log, "alpha", eval::methodRigs(run.rig),
                                        run.o.settings, false,
                                        [&](int mode) -> Group& { return calib_groups[mode]; }));
    in.timings_s["evaluate_alpha_log"] = roundTo(w.seconds(), 6);
  }
  std::vector<const SweepRecord*> calib_records;
  for (const auto& [mode, g] : calib_groups) {
    for (const auto& r : g.sweeps) calib_records.push_back(&r);
  }
  {
    Stopwatch w;
    const double alpha0 = run.rig.plate.alpha_deg * kDegToRad;
    in.alpha = eval::calibrateAlpha(calib_records, Method::kRayPlane, alpha0);
    in.alpha_centroid = eval::calibrateAlpha(calib_records, Method::kCentroid, alpha0);
    in.timings_s["alpha_calibration"] = roundTo(w.seconds(), 6);
  }
  in.alpha_source = std::to_string(run.o.calib_sweeps) + " simulated mode-7 sweeps";
  if (!in.alpha.done) {
    throw std::runtime_error("alpha calibration failed: " + in.alpha.reason);
  }
  // The modes are evaluated with these (the centroid method falls back to the rig's alpha).
  in.alpha_applied = true;
  in.alpha_eval_deg = in.alpha.lm.alpha_rad * kRadToDeg;
  in.alpha_eval_centroid_deg =
      in.alpha_centroid.done ? in.alpha_centroid.lm.alpha_rad * kRadToDeg : run.rig.plate.alpha_deg;
  progressLine(run.o.settings, "alpha calibrated: " + fixed(in.alpha_eval_deg, 4) +
                                   " deg (ray_plane), " + fixed(in.alpha_eval_centroid_deg, 4) +
                                   " deg (centroid), from " + std::to_string(in.alpha.sweeps_used) +
                                   " sweeps");
}

// DIR/plate_calibration.yaml: the alpha of the default method.
void writePlateCalibrationFile(const PaperRun& run, const std::string& calib_log) {
  PlateCalibration pc;
  pc.alpha_deg = run.in.alpha_eval_deg;
  pc.source = {{"tool", "sweepmap eval (rotating_lidar) --experiment paper"},
               {"method", "LM over wall normals (Yuan 2021 Algorithm A1), beta by ray_plane"},
               {"sweeps", std::to_string(run.in.alpha.sweeps_used)}};
  pc.logs = {fs::path(calib_log).filename().string()};
  writePlateCalibration((run.out / "plate_calibration.yaml").string(), pc);
}

// The rig the modes are evaluated with: the calibrated alpha of each method, no calibration file.
MethodRigs calibratedRigs(const PaperRun& run) {
  RotatingLidarConfig eval_rig = run.rig;
  eval_rig.plate.calibration_file.clear();
  MethodRigs rigs = eval::methodRigs(eval_rig);
  rigs.ray_plane.plate.alpha_deg = run.in.alpha_eval_deg;
  rigs.centroid.plate.alpha_deg = run.in.alpha_eval_centroid_deg;
  return rigs;
}

// 2. The 7 modes x N sweeps.
void evaluateModes(PaperRun& run, const MethodRigs& rigs) {
  const EvalSettings& s = run.o.settings;
  for (int mode = 1; mode <= 7; ++mode) {
    const std::string file = "mode" + std::to_string(mode) + ".lcmlog";
    const std::string path =
        simulateLog(run, file, mode, "improved", run.o.sweeps_per_mode, run.o.seed + mode);
    Stopwatch w;
    run.in.logs.push_back(eval::evaluateLog(path, "mode", rigs, s, s.plots,
                                            [&](int m) -> Group& { return run.in.modes[m]; }));
    run.in.timings_s["evaluate_" + file] = roundTo(w.seconds(), 6);
  }
}

// 3. Mode 1 with the naive action sequence (shape error, Fig. 1).
void evaluateNaive(PaperRun& run, const MethodRigs& rigs) {
  const EvalSettings& s = run.o.settings;
  const std::string path =
      simulateLog(run, "mode1_naive.lcmlog", 1, "naive", run.o.sweeps_per_mode, run.o.seed + 200);
  Stopwatch w;
  run.in.naive.emplace();
  run.in.logs.push_back(eval::evaluateLog(path, "naive", rigs, s, s.plots,
                                          [&](int) -> Group& { return *run.in.naive; }));
  run.in.timings_s["evaluate_mode1_naive.lcmlog"] = roundTo(w.seconds(), 6);
}

}  // namespace

// --- entry points ------------------------------------------------------------------------

EvalRotatingResult evalRotatingLogs(const EvalRotatingOptions& o) {
  Stopwatch total;
  if (o.logs.empty()) throw std::runtime_error("no logs given");
  for (const auto& l : o.logs) {
    if (!fs::exists(l)) throw std::runtime_error(l + ": no such log");
  }
  const fs::path out(o.out_dir);
  fs::create_directories(out);
  const EvalSettings& s = o.settings;
  const MethodRigs rigs = eval::methodRigs(o.rig);

  ReportInput in;
  in.inputs.logs = o.logs;
  in.inputs.rig = o.rig_path;
  in.inputs.overrides = o.overrides;
  in.mapper = o.rig.mapper;
  for (size_t i = 0; i < o.logs.size(); ++i) {
    progressLine(
        s, "log " + std::to_string(i + 1) + "/" + std::to_string(o.logs.size()) + ": " + o.logs[i]);
    in.logs.push_back(eval::evaluateLog(o.logs[i], "input", rigs, s, s.plots,
                                        [&](int mode) -> Group& { return in.modes[mode]; }));
  }
  in.alpha_true_rad = firstAlphaTruth(in.logs);
  in.alpha_source = "the mode-7 sweeps of the logs";
  const double alpha0 = o.rig.plate.alpha_deg * kDegToRad;
  Stopwatch lm_watch;
  in.alpha = eval::calibrateAlpha(mode7Records(in.modes), Method::kRayPlane, alpha0);
  in.alpha_centroid = eval::calibrateAlpha(mode7Records(in.modes), Method::kCentroid, alpha0);
  in.alpha_eval_deg = in.alpha_eval_centroid_deg = o.rig.plate.alpha_deg;
  in.timings_s["evaluate_logs"] = roundTo(total.seconds() - lm_watch.seconds(), 6);
  in.timings_s["alpha_calibration"] = roundTo(lm_watch.seconds(), 6);
  in.timings_s["total"] = roundTo(total.seconds(), 6);
  return finish(out, in, s, total);
}

EvalRotatingResult runPaperExperiment(const PaperExperimentOptions& o) {
  Stopwatch total;
  PaperRun run = startPaperRun(o);
  const std::string calib_log =
      simulateLog(run, "alpha_mode7.lcmlog", 7, "improved", o.calib_sweeps, o.seed + 100);
  calibrateAlphaFromLog(run, calib_log);
  writePlateCalibrationFile(run, calib_log);
  const MethodRigs rigs = calibratedRigs(run);
  evaluateModes(run, rigs);
  if (o.naive) evaluateNaive(run, rigs);
  run.in.alpha_true_rad = firstAlphaTruth(run.in.logs);
  run.in.timings_s["total_before_report"] = roundTo(total.seconds(), 6);
  return finish(run.out, run.in, o.settings, total);
}

}  // namespace sweepmap
