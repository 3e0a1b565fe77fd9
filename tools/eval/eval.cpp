#include "tools/eval/eval.hpp"

#include "rigs/rig_file.hpp"
#include "tools/eval/eval_mobile.hpp"
#include "tools/eval/eval_profile.hpp"
#include "tools/eval/eval_rotating.hpp"

namespace sweepmap {

namespace {

EvalRunResult evalRotating(const EvalRequest& q, const Rig& rig) {
  if (q.compare_uncalibrated) {
    throw ConfigError("--compare-uncalibrated applies to mobile_lidar rigs; " + rig.path +
                      " is a rotating_lidar rig");
  }
  EvalSettings settings;
  settings.plots = q.plots;
  settings.progress = q.progress;
  EvalRotatingResult r;
  if (!q.experiment.empty()) {
    PaperExperimentOptions po;
    po.rig_path = rig.path;
    if (!q.scene.empty()) po.scene_path = q.scene;
    po.overrides = q.overrides;
    po.out_dir = q.out_dir;
    po.seed = q.seed;
    if (q.sweeps_per_mode > 0) po.sweeps_per_mode = q.sweeps_per_mode;
    if (q.calib_sweeps > 0) po.calib_sweeps = q.calib_sweeps;
    po.naive = !q.no_naive;
    po.settings = settings;
    r = runPaperExperiment(po);
  } else {
    EvalRotatingOptions eo;
    eo.rig = std::get<RotatingLidarConfig>(rig.config);
    eo.rig_path = rig.path;
    eo.overrides = q.overrides;
    eo.logs = q.logs;
    eo.out_dir = q.out_dir;
    eo.settings = settings;
    r = evalRotatingLogs(eo);
  }
  return {r.failed,
          std::to_string(r.sweeps) + " sweeps, " + std::to_string(r.figures.size()) +
              " figures -> " + q.out_dir + "/report.md",
          r.message};
}

EvalRunResult evalMobile(const EvalRequest& q, const Rig& rig) {
  if (q.sweeps_per_mode > 0 || q.calib_sweeps > 0 || q.no_naive) {
    throw ConfigError(
        "--sweeps-per-mode, --calib-sweeps and --no-naive apply to rotating_lidar "
        "rigs; " +
        rig.path + " is a mobile_lidar rig");
  }
  EvalMobileResult r;
  if (!q.experiment.empty()) {
    MobileExperimentOptions mo;
    mo.rig_path = rig.path;
    if (!q.scene.empty()) mo.scene_path = q.scene;
    mo.overrides = q.overrides;
    mo.out_dir = q.out_dir;
    mo.seed = q.seed;
    mo.plots = q.plots;
    mo.progress = q.progress;
    r = runMobilePaperExperiment(mo);
  } else {
    if (q.logs.size() != 1) {
      throw ConfigError("a mobile_lidar rig evaluates one log at a time (" +
                        std::to_string(q.logs.size()) + " given)");
    }
    EvalMobileOptions eo;
    eo.rig = std::get<MobileLidarConfig>(rig.config);
    eo.log_path = q.logs.front();
    eo.out_dir = q.out_dir;
    eo.plots = q.plots;
    eo.progress = q.progress;
    if (q.compare_uncalibrated) {
      LidarMounting before = eo.rig.mounting.toMounting();
      before.gamma_rad = before.beta_rad = before.alpha_rad = 0.0;
      eo.before = before;
    }
    r = evalMobileLog(eo);
  }
  return {r.failed, "-> " + q.out_dir + "/report.json", r.message};
}

EvalRunResult evalProfile(const EvalRequest& q, const Rig& rig) {
  if (q.experiment.empty()) {
    throw ConfigError("a rotating_profile rig is evaluated by --experiment paper (" + rig.path +
                      "); its logs are calibrated by `sweepmap calib axis-offset`");
  }
  if (q.sweeps_per_mode > 0 || q.calib_sweeps > 0 || q.no_naive || q.compare_uncalibrated) {
    throw ConfigError(
        "--sweeps-per-mode, --calib-sweeps, --no-naive and --compare-uncalibrated do not apply "
        "to rotating_profile rigs (" +
        rig.path + ")");
  }
  if (!q.scene.empty()) {
    throw ConfigError(
        "--scene does not apply to rotating_profile rigs: the experiment scans "
        "the plate, then the test piece");
  }
  ProfileExperimentOptions po;
  po.rig_path = rig.path;
  po.overrides = q.overrides;
  po.out_dir = q.out_dir;
  po.seed = q.seed;
  if (q.repeats >= 0) po.repeats = q.repeats;
  po.plots = q.plots;
  po.progress = q.progress;
  const EvalProfileResult r = runProfilePaperExperiment(po);
  return {r.failed,
          std::to_string(r.scans) + " test-piece scans, " + std::to_string(r.figures) +
              " figures -> " + q.out_dir + "/report.md",
          r.message};
}

}  // namespace

EvalRunResult runEval(const EvalRequest& q) {
  if (q.logs.empty() == q.experiment.empty()) {
    throw ConfigError("give --logs LOG... or --experiment paper");
  }
  // With logs the overrides are the rig's; with an experiment scene.<key> goes to the scene
  // and the loaders of the experiment apply them.
  const Rig rig = loadRig(q.rig, q.experiment.empty() ? q.overrides : std::vector<std::string>{});
  if (q.repeats >= 0 && rig.kind() != RigKind::kRotatingProfile) {
    throw ConfigError("--repeats applies to rotating_profile rigs; " + rig.path + " is a " +
                      rig.kindName() + " rig");
  }
  switch (rig.kind()) {
    case RigKind::kRotatingLidar:
      return evalRotating(q, rig);
    case RigKind::kMobileLidar:
      return evalMobile(q, rig);
    case RigKind::kRotatingProfile:
      return evalProfile(q, rig);
  }
  throw ConfigError(rig.path + ": no evaluation for rig kind " + rig.kindName());
}

}  // namespace sweepmap
