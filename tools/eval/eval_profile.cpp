// Rig C's paper experiment step by step (see the header): simulate, calibrate both ways,
// scan the test piece, measure under each setting, report.
#include "tools/eval/eval_profile.hpp"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "core/angles.hpp"
#include "core/event_log.hpp"
#include "rigs/rig_file.hpp"
#include "tools/eval/common.hpp"
#include "tools/eval/eval_profile_figures.hpp"
#include "tools/eval/eval_profile_report.hpp"
#include "tools/offline/calibrate_axis_offset.hpp"
#include "tools/offline/profile_log.hpp"
#include "tools/offline/sim_profile.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;
using eval::fixed;
using eval::ProfileEvaluation;
using eval::ProfileSetting;

// Zhao 2021 Table 2's wrong settings relative to its optimum (110/395 and 130/425 against
// 123/409), applied to the truth.
constexpr double kTooSmallM = -13.0, kTooSmallN = -14.0;
constexpr double kTooLargeM = 7.0, kTooLargeN = 16.0;
// Test-piece scan K: the piece (K - (repeats - 1) / 2) * this nearer or farther than the
// rig's distance, and the sweep's end moved by K / repeats of a profile step (the profiles
// fall elsewhere on the piece).
constexpr double kDistanceStep_mm = 3.0;

RotatingProfileConfig loadProfileRig(const ProfileExperimentOptions& o,
                                     const std::vector<std::string>& extra) {
  // The paper's part has none of a real part's artefacts (mixed pixels, dropouts); the user's
  // --set still wins.
  std::vector<std::string> sets = SimProfileConfig::artefactsOff();
  sets.insert(sets.end(), o.overrides.begin(), o.overrides.end());
  sets.insert(sets.end(), extra.begin(), extra.end());
  const Rig rig = sweepmap::loadRig(o.rig_path, sets);
  RotatingProfileConfig c = requireKind<RotatingProfileConfig>(rig, "this experiment");
  return c;
}

// Simulates the rig into DIR/logs/NAME.lcmlog and reads it back as the calibration reads logs.
ProfileLog simulateLog(const ProfileExperimentOptions& o, const RotatingProfileConfig& rig,
                       const std::string& name, uint64_t seed, ProfileEvaluation* ev) {
  const fs::path log = fs::path(o.out_dir) / "logs" / (name + ".lcmlog");
  {
    EventLogWriter w(log.string());
    simulateRotatingProfile(rig, seed,
                            [&](const Message& m) { w.write(m.utime, m.channel, m.data); });
    w.close();
  }
  ev->logs.push_back("logs/" + name + ".lcmlog");
  return readProfileLog(log.string());
}

// Step 1: the plate, both calibrations, S(M, N).
void calibrate(const ProfileExperimentOptions& o, ProfileEvaluation* ev) {
  const RotatingProfileConfig rig = loadProfileRig(o, {"sim.scene=plate"});
  eval::progressLine(o.progress, "simulating " + std::to_string(rig.sim.plate_count) +
                                     " plate poses -> " + o.out_dir + "/logs/plate.lcmlog");
  const ProfileLog log = simulateLog(o, rig, "plate", o.seed, ev);
  if (!log.truth) throw std::runtime_error("the simulated plate log has no TRUTH_PROFILE_RIG");
  ev->truth = log.truth->geometry;
  ev->nominal = rig.geometry.toGeometry();
  ev->profiler = rig.profiler;
  ev->turntable = rig.turntable;
  ev->range_noise_sigma_mm = rig.sim.range_noise_sigma_mm;
  ev->encoder_noise_counts = rig.sim.encoder_noise_counts;
  // The same evenly strided subset as `sweepmap calib axis-offset`, for both methods.
  const int max_points = AxisOffsetCalibRequest{}.max_points_per_sweep;
  std::vector<PlanePoints> planes;
  for (const PlanePoints& sweep : log.sweeps) {
    ev->plate_points.push_back(sweep.samples.size());
    planes.push_back(subsample(sweep, max_points));
    ev->plate_points_used.push_back(planes.back().samples.size());
  }
  eval::progressLine(o.progress, "the paper's grid search (1 mm) and ours (Ceres)");
  ev->grid = gridSearchAxisOffset(planes, ev->grid_options);
  AxisOffsetOptions ao;
  ao.initial = ev->nominal;
  ev->ours = solveAxisOffset(planes, ao);
  eval::progressLine(o.progress, "ours M " + fixed(ev->ours.geometry.m_mm, 3) + ", N " +
                                     fixed(ev->ours.geometry.n_mm, 3) + " mm (" +
                                     fixed(ev->ours.seconds, 3) + " s); grid M " +
                                     fixed(ev->grid.m_mm, 0) + ", N " + fixed(ev->grid.n_mm, 0) +
                                     " mm (" + fixed(ev->grid.seconds, 3) + " s)");
}

// The four settings of Table 2's columns (ours first). The grid's and the wrong ones use the
// paper's model, Eq. 7: no tilt, no encoder zero.
std::vector<ProfileSetting> settingsOf(const ProfileEvaluation& ev) {
  const auto paper = [](double m, double n) { return ProfileGeometry{m, n, 0.0, 0.0}; };
  const ProfileGeometry& t = ev.truth;
  return {{"ours", "ours (Ceres)", ev.ours.geometry, {}, {}},
          {"grid", "paper's grid (1 mm)", paper(ev.grid.m_mm, ev.grid.n_mm), {}, {}},
          {"too_small", "M - 13, N - 14", paper(t.m_mm + kTooSmallM, t.n_mm + kTooSmallN), {}, {}},
          {"too_large", "M + 7, N + 16", paper(t.m_mm + kTooLargeM, t.n_mm + kTooLargeN), {}, {}}};
}

// Step 2 and 3: every scan of the test piece under every setting.
void measure(const ProfileExperimentOptions& o, ProfileEvaluation* ev) {
  ev->settings = settingsOf(*ev);
  const RotatingProfileConfig base = loadProfileRig(o, {"sim.scene=test_piece"});
  const double middle_rad =
      0.5 * (base.turntable.sweep_start_deg + base.turntable.sweep_end_deg) * kDegToRad;
  const double step_deg = base.turntable.speed_deg_s / base.profiler.profile_rate_hz;
  for (int k = 0; k < o.repeats; ++k) {
    const double distance =
        base.sim.test_piece.distance_mm + kDistanceStep_mm * (k - 0.5 * (o.repeats - 1));
    const double end = base.turntable.sweep_end_deg + step_deg * k / o.repeats;
    const RotatingProfileConfig rig = loadProfileRig(
        o, {"sim.scene=test_piece", "sim.test_piece.distance_mm=" + fixed(distance, 6),
            "turntable.sweep_end_deg=" + fixed(end, 9)});
    const std::string name = "test_piece_" + std::to_string(k);
    eval::progressLine(o.progress, "scan " + std::to_string(k + 1) + "/" +
                                       std::to_string(o.repeats) + ": the piece " +
                                       fixed(distance, 1) + " mm below -> logs/" + name +
                                       ".lcmlog");
    const ProfileLog log = simulateLog(o, rig, name, o.seed + 100 + k, ev);
    if (!log.test_piece || log.sweeps.empty()) {
      throw std::runtime_error("logs/" + name + ".lcmlog has no TRUTH_TEST_PIECE or no profiles");
    }
    ev->piece = log.test_piece->sizes;  // the same true sizes in every scan
    for (ProfileSetting& s : ev->settings) {
      eval::PieceMeasurement m =
          eval::measureTestPiece(log.sweeps.front().samples, s.geometry, middle_rad);
      s.sizes_mm.push_back(m.size_mm);
      for (const auto& p : m.problems) s.problems.push_back("scan " + std::to_string(k) + ": " + p);
      if (k == 0 && s.name == "ours") ev->example = std::move(m);
    }
  }
}

}  // namespace

EvalProfileResult runProfilePaperExperiment(const ProfileExperimentOptions& o) {
  if (o.repeats < 2) throw ConfigError("--repeats must be at least 2 (a mean and a spread)");
  EvalProfileResult result;
  const fs::path out(o.out_dir);
  fs::create_directories(out / "logs");
  ProfileEvaluation ev;
  ev.rig_path = resolveRigFile(o.rig_path);
  ev.seed = o.seed;
  ev.repeats = o.repeats;
  try {
    calibrate(o, &ev);
    measure(o, &ev);
  } catch (const ConfigError&) {
    throw;
  } catch (const std::exception& e) {  // a log that does not read back, a failed fit
    result.failed = true;
    result.message = e.what();
    return result;
  }
  Figures figures(out, o.plots);
  eval::drawProfileFigures(ev, &figures);
  eval::writeProfileReport(out, ev, figures.files(), figures.errors());
  result.figures = static_cast<int>(figures.files().size());
  result.scans = o.repeats;
  for (const ProfileSetting& s : ev.settings) {
    if (!s.problems.empty()) {
      result.failed = true;
      result.message = s.name + ": " + s.problems.front();
      break;
    }
  }
  if (!ev.ours.observable) {
    result.failed = true;
    result.message = "ours: M and N not determined by the plates";
  }
  return result;
}

}  // namespace sweepmap
