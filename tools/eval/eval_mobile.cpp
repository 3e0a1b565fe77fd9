// The two ways to evaluate rig B: one log (evalMobileLog) and the simulated paper experiment
// (runMobilePaperExperiment), each in steps. The measures are in mobile_metrics, the figures
// in mobile_figures, report.json and report.md in mobile_report.
#include "tools/eval/eval_mobile.hpp"

#include <filesystem>

#include "calib/cloud_density.hpp"
#include "calib/mounting_calibration.hpp"
#include "core/calibration_file.hpp"
#include "core/event_log.hpp"
#include "mapping/cloud_io.hpp"
#include "sim/scene.hpp"
#include "tools/eval/common.hpp"
#include "tools/eval/mobile_figures.hpp"
#include "tools/eval/mobile_metrics.hpp"
#include "tools/eval/mobile_report.hpp"
#include "tools/offline/mobile_log.hpp"
#include "tools/offline/runs.hpp"
#include "tools/offline/sim_mobile.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;
using eval::CircleCalibration;
using eval::fixed;
using eval::MobileEvaluation;

// --- one log ------------------------------------------------------------------------------

// Replays the log's odometry. A log that cannot be read, is corrupt or holds no scans or
// poses fails the result; what there is is evaluated all the same.
MobileEvaluation loadEvaluation(const EvalMobileOptions& o, EvalMobileResult* result) {
  MobileEvaluation ev;
  ev.log_name = fs::path(o.log_path).filename().string();
  eval::progressLine(o.progress, "replaying the odometry over " + o.log_path);
  try {
    ev.log = loadMobileLog(o.log_path, o.rig);
  } catch (const std::exception& e) {
    result->failed = true;
    result->message = e.what();
  }
  if (ev.log.log_error) {
    result->failed = true;
    result->message = ev.log.error;
  }
  if (ev.log.scans.empty() || ev.log.ekf.size() == 0) {
    result->failed = true;
    if (result->message.empty())
      result->message = o.log_path + ": no valid scans or no odometry poses";
  }
  ev.pose_channel = o.rig.assembler.pose_channel;
  ev.mounting = o.rig.mounting.toMounting();
  return ev;
}

// Trajectory errors, the world-frame cloud (written to out/cloud.pcd and .ply), the room's planes
// (also with the mounting before calibration, when given), the density and the loop's ghost.
void measure(const EvalMobileOptions& o, const fs::path& out, MobileEvaluation* ev) {
  ev->odometry = eval::trajectoryErrors(ev->log.wheels, ev->log.truth);
  ev->ekf = eval::trajectoryErrors(ev->log.ekf, ev->log.truth);
  eval::progressLine(o.progress, "assembling " + std::to_string(ev->log.scans.size()) +
                                     " scans in the world frame");
  ev->cloud = assembleWorld(ev->log, ev->track(), ev->mounting, &ev->scan_of_point);
  writePcdAndPly((out / "cloud").string(), ev->cloud);
  eval::progressLine(o.progress, "RANSAC planes");
  ev->room = eval::measureRoom(ev->cloud);
  ev->room.dims =
      eval::refinedRoomDims(ev->log, ev->track(), ev->cloud, ev->scan_of_point, ev->mounting,
                            ev->room.planes, o.rig.sim.range_sigma_fraction);
  if (o.before) {
    eval::progressLine(o.progress, "the same with the mounting before calibration");
    ev->before_mounting = *o.before;
    ev->before = eval::measureRoom(assembleWorld(ev->log, ev->track(), *o.before));
  }
  eval::progressLine(o.progress, "density D over " + std::to_string(ev->cloud.size()) + " points");
  ev->density_m = meanNearestNeighbourDistance(ev->cloud);
  eval::progressLine(o.progress, "loop closure");
  // The room's walls, each pass's band by the rig's range noise (its simulated lidar's, the
  // X4's 1 %).
  ev->loop = eval::loopClosure(ev->log, ev->track(), ev->cloud, ev->scan_of_point, ev->mounting,
                               ev->room.planes.walls, o.rig.sim.range_sigma_fraction);
}

// evalMobileLog; the paper experiment adds its calibration from the circle and the figures it
// drew (listed first).
EvalMobileResult evaluate(const EvalMobileOptions& o, const CircleCalibration* circle,
                          const std::vector<Figures::Entry>& circle_figures) {
  EvalMobileResult result;
  const fs::path out(o.out_dir);
  fs::create_directories(out);
  MobileEvaluation ev = loadEvaluation(o, &result);
  measure(o, out, &ev);
  Figures figures(out, o.plots);
  eval::drawMobileFigures(ev, &figures);
  std::vector<Figures::Entry> all_figures = circle_figures;
  all_figures.insert(all_figures.end(), figures.files().begin(), figures.files().end());
  eval::writeMobileReport(out, ev, circle, all_figures, figures.errors());
  return result;
}

// --- the paper experiment, step by step -----------------------------------------------------

// One of the paper's two runs (the calibration circle, r = 0.83 m, or one lap of the lab loop,
// at 0.2 m/s), from the same rig and scene files, into DIR/logs/<name>.lcmlog; returns its
// path, and the rig and scene it was simulated with.
std::string simulateRun(const MobileExperimentOptions& o, const std::string& name,
                        const std::string& path, double duration_s, uint64_t seed,
                        MobileLidarConfig* rig, SceneConfig* scene) {
  // The paper's setting: its car's odometry taken as exact (it calibrates the mounting alone),
  // so the build errors of a real car (sim/mobile.hpp) are off unless the caller sets them, and
  // its lab has none of the scene's artefacts.
  std::vector<std::string> overrides = paperMobileSettings();
  overrides.insert(overrides.end(), o.overrides.begin(), o.overrides.end());
  overrides.push_back("sim.path=" + path);
  overrides.push_back("sim.duration_s=" + fixed(duration_s, 3));
  SimMobileOptions so;
  const SimSetup setup = loadSimSetup(o.rig_path, o.scene_path, overrides);
  so.rig = requireKind<MobileLidarConfig>(setup.rig, "this experiment");
  so.scene = setup.scene;
  so.seed = seed;
  const std::string log_path = (fs::path(o.out_dir) / "logs" / (name + ".lcmlog")).string();
  eval::progressLine(o.progress,
                     "simulating the " + name + " (" + fixed(duration_s, 0) + " s) -> " + log_path);
  EventLogWriter w(log_path);
  simulateMobile(so, [&](const Message& m) { w.write(m.utime, m.channel, m.data); });
  w.close();
  *rig = so.rig;
  *scene = so.scene;
  return log_path;
}

// Both methods on the circle, from the rig file's mounting `initial`.
CircleCalibration calibrateFromCircle(const MobileLog& circle, const LidarMounting& initial) {
  CircleCalibration c;
  if (circle.truth_mounting) c.truth = trueMounting(*circle.truth_mounting);
  MountingCalibrationOptions ours_options;
  ours_options.method = MountingMethod::kPointToPlane;
  MountingCalibrationOptions paper_options;
  paper_options.method = MountingMethod::kPaperPoints;
  c.ours = calibrateMounting(circle.scans, circle.ekf, initial, ours_options);
  c.paper = calibrateMounting(circle.scans, circle.ekf, initial, paper_options);
  return c;
}

void writeMountingCalibrationFile(const fs::path& out, const MountingCalibrationResult& ours) {
  MountingCalibration file;
  file.gamma_rad = ours.gamma_rad;
  file.beta_rad = ours.beta_rad;
  file.alpha_rad = ours.alpha_rad;
  file.source["tool"] = "sweepmap eval --experiment paper (mobile_lidar)";
  file.source["method"] = mountingMethodName(ours.method);
  file.logs = {"logs/circle.lcmlog"};
  writeMountingCalibration((out / "mounting_calibration.yaml").string(), file);
}

// The calibration target's box in the world frame: the scene's room frame moved by
// TRUTH_MOUNTING's start pose. None without a target or the truth.
std::optional<Eigen::AlignedBox3d> targetInWorld(const SceneConfig& scene,
                                                 const MobileLog& circle) {
  const auto board = Scene(scene, PlateConfig{}).targetBoard();
  if (!board || !circle.truth_mounting) return std::nullopt;
  const double* w = circle.truth_mounting->world_in_room;
  const Eigen::Isometry3d T_world_room = planarToIsometry(Pose2{w[0], w[1], w[2]}).inverse();
  Eigen::AlignedBox3d target_world(T_world_room * board->min());
  target_world.extend(T_world_room * board->max());
  return target_world;
}

// The circle's double walls before and after the calibration (Fig. 6-7) into
// `calibration`, and their figures (and a close-up of the target); returns the figures drawn.
std::vector<Figures::Entry> circleDoubleWalls(const MobileExperimentOptions& o,
                                              const MobileLog& circle, const SceneConfig& scene,
                                              double range_sigma_fraction,
                                              const LidarMounting& initial,
                                              const LidarMounting& calibrated,
                                              CircleCalibration* calibration) {
  eval::progressLine(o.progress, "double walls of the circle before and after calibration");
  const std::optional<Eigen::AlignedBox3d> target_world = targetInWorld(scene, circle);
  Figures figures(o.out_dir, o.plots);
  for (const auto& [name, mounting] :
       {std::pair<std::string, LidarMounting>{"before", initial}, {"after", calibrated}}) {
    const eval::HalfScanGhost g =
        eval::halfScanGhost(circle, circle.ekf, mounting, range_sigma_fraction);
    calibration->double_walls[name] = g.walls;
    eval::circleGhostFigure(name, g, &figures);
    if (target_world) eval::targetGhostFigure(name, g, *target_world, &figures);
  }
  return figures.files();
}

}  // namespace

EvalMobileResult evalMobileLog(const EvalMobileOptions& o) { return evaluate(o, nullptr, {}); }

EvalMobileResult runMobilePaperExperiment(const MobileExperimentOptions& o) {
  const fs::path out(o.out_dir);
  fs::create_directories(out / "logs");
  MobileLidarConfig circle_rig, loop_rig;
  SceneConfig scene;
  const std::string circle_log =
      simulateRun(o, "circle", "circle", o.circle_duration_s, o.seed, &circle_rig, &scene);
  const std::string loop_log =
      simulateRun(o, "loop", "loop", o.loop_duration_s, o.seed + 1, &loop_rig, &scene);

  eval::progressLine(o.progress,
                     "calibrating the mounting from the circle (ours: point-to-plane; the paper's: "
                     "target points)");
  const MobileLog circle = loadMobileLog(circle_log, circle_rig);
  const LidarMounting initial = circle_rig.mounting.toMounting();
  CircleCalibration calibration = calibrateFromCircle(circle, initial);
  const MountingCalibrationResult& ours = calibration.ours;
  if (!ours.ok) {
    eval::writeCalibrationFailureReport(out, calibration);
    return {true, "mounting calibration failed: " + ours.reason};
  }
  LidarMounting calibrated = initial;
  calibrated.gamma_rad = ours.gamma_rad;
  calibrated.beta_rad = ours.beta_rad;
  calibrated.alpha_rad = ours.alpha_rad;
  writeMountingCalibrationFile(out, ours);
  const std::vector<Figures::Entry> circle_figures = circleDoubleWalls(
      o, circle, scene, circle_rig.sim.range_sigma_fraction, initial, calibrated, &calibration);

  // The loop with our calibration, beside the mounting before it.
  EvalMobileOptions eo;
  eo.log_path = loop_log;
  eo.rig = loop_rig;
  eo.rig.mounting.gamma_rad = ours.gamma_rad;
  eo.rig.mounting.beta_rad = ours.beta_rad;
  eo.rig.mounting.alpha_rad = ours.alpha_rad;
  eo.out_dir = o.out_dir;
  eo.plots = o.plots;
  eo.progress = o.progress;
  eo.before = initial;
  eval::progressLine(o.progress, "evaluating the loop with our calibration");
  return evaluate(eo, &calibration, circle_figures);
}

}  // namespace sweepmap
