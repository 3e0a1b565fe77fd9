#include "tools/bench/bench_calibration.hpp"

#include <sys/resource.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <variant>

#include "calib/mounting_calibration.hpp"
#include "core/set_arguments.hpp"
#include "sim/mobile.hpp"
#include "tools/bench/proc_stats.hpp"
#include "tools/offline/calibrate_rig.hpp"
#include "tools/offline/mobile_log.hpp"

namespace sweepmap {
namespace {

using nlohmann::json;

// The paper's setting for rig B's circle (tools/eval/eval_mobile.cpp): the car's odometry
// exact, so the single-parameter `calib mounting` (which assumes it) is measured on what it
// was measured on when its reference solver took 442 s (before the build errors and the
// scene's artefacts existed).
const std::vector<std::string> kExactOdometry = paperMobileSettings();

// `sweepmap sim --rig RIG ARGS --out LOG` as a child; false (said on `out`) if it failed.
bool simulateLog(const CalibrationBenchOptions& o, const Rig& rig,
                 const std::vector<std::string>& sim_args, const std::string& log,
                 std::ostream& out) {
  std::vector<std::string> args = {o.sweepmap_exe, "sim", "--rig", rig.path};
  args.insert(args.end(), sim_args.begin(), sim_args.end());
  args.insert(args.end(), {"--out", log});
  const ChildRun sim = runChild(args, log + ".txt", log + ".txt");
  if (!sim.ok) out << "  sweepmap sim failed (see " << log << ".txt)\n";
  return sim.ok;
}

// `sweepmap calib rig --json` on `log` as a child: its run, and its JSON (null if it failed or
// printed no parameters).
json calibRig(const CalibrationBenchOptions& o, const Rig& rig, const std::string& log,
              ChildRun* run, const std::string& suffix = "") {
  const std::string stem = o.work + "/calib_rig_" + rig.kindName() + suffix;
  *run = runChild({o.sweepmap_exe, "calib", "rig", "--rig", rig.path, "--logs", log, "--out",
                   stem + ".yaml", "--json"},
                  stem + ".json", stem + ".txt");
  if (!run->ok) return nullptr;
  std::ifstream f(stem + ".json");
  json j = json::parse(f, nullptr, false);
  if (j.is_discarded() || !j.contains("parameters")) return nullptr;
  return j;
}

// One line per parameter with a truth: its value, sigma and error (also in sigmas), and per
// measure with a truth (rig B's room) its error.
void printErrors(const json& r, std::ostream& out) {
  for (const auto& [key, p] : r.at("parameters").items()) {
    if (!p.contains("truth") || !p["value"].is_number() || !p["truth"].is_number()) continue;
    const double value = p["value"], truth = p["truth"];
    const double sigma = p["sigma"].is_number() ? p["sigma"].get<double>() : NAN;
    out << "    " << std::left << std::setw(30) << key << std::right << std::setprecision(6)
        << std::setw(12) << value << " " << std::left << std::setw(6)
        << p.value("unit", std::string()) << std::right << " error " << std::setw(10)
        << value - truth;
    if (std::isfinite(sigma) && sigma > 0)
      out << " = " << std::setprecision(2) << (value - truth) / sigma << " sigma";
    if (!p.value("observable", true)) out << " (not observable: left nominal)";
    out << "\n";
  }
  if (!r.contains("measures")) return;
  for (const auto& [key, m] : r["measures"].items()) {
    if (!m.contains("truth") || !m["truth"].is_number()) continue;
    out << "    " << std::left << std::setw(30) << key << std::right << std::setprecision(4)
        << std::setw(12) << m["value"].get<double>() << " " << m.value("unit", std::string())
        << " error " << std::setprecision(1)
        << (m["value"].get<double>() - m["truth"].get<double>()) * 1e3 << " mm\n";
  }
}

// The mounting error (gamma, beta, alpha) in mrad of a calib rig JSON; nullopt without truth.
std::optional<Eigen::Vector3d> mountingError(const json& r) {
  Eigen::Vector3d e;
  int i = 0;
  for (const char* k : {"mounting.gamma_rad", "mounting.beta_rad", "mounting.alpha_rad"}) {
    const json& p = r.at("parameters").value(k, json());
    if (!p.is_object() || !p.contains("truth")) return std::nullopt;
    e[i++] = (p["value"].get<double>() - p["truth"].get<double>()) * 1e3;
  }
  return e;
}

struct MountingRun {
  double wall_s = 0.0, cpu_s = 0.0;
  Eigen::Vector3d error_mrad = Eigen::Vector3d::Zero();
  bool ok = false;
};

// `calib mounting`'s point-to-plane solver on the circle in this process: the reference one
// (the command before issue 23) or today's; wall and CPU time, error against the truth.
MountingRun runMounting(const MobileLog& log, const LidarMounting& initial, bool reference) {
  MountingCalibrationOptions options;
  options.reference_solver = reference;
  const double cpu0 = cpuSeconds(RUSAGE_SELF);
  const auto t0 = BenchClock::now();
  const MountingCalibrationResult r = calibrateMounting(log.scans, log.ekf, initial, options);
  MountingRun m;
  m.wall_s = secondsSince(t0);
  m.cpu_s = cpuSeconds(RUSAGE_SELF) - cpu0;
  m.ok = r.ok;
  const LidarMounting truth = trueMounting(*log.truth_mounting);
  m.error_mrad = 1e3 * Eigen::Vector3d(r.gamma_rad - truth.gamma_rad, r.beta_rad - truth.beta_rad,
                                       r.alpha_rad - truth.alpha_rad);
  return m;
}

std::string mrad(const Eigen::Vector3d& e) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(3) << e[0] << ", " << e[1] << ", " << e[2] << " mrad";
  return s.str();
}

// Rig B: the old single-parameter command and today's on the circle, against calib rig in the
// same run on as much driving: the plan's drive cut to the circle's length.
void benchOldMounting(const CalibrationBenchOptions& o, const Rig& rig, std::ostream& out) {
  RigBRecording cut_recording;
  cut_recording.duration_s = int(std::lround(o.mounting_circle_s));
  const std::vector<std::string> cut = setArguments(rigBRecordingSets(cut_recording));
  const std::string cut_path = o.work + "/calib_plan_cut.lcmlog";
  if (!simulateLog(o, rig, cut, cut_path, out)) return;
  ChildRun joint;
  const json joint_json = calibRig(o, rig, cut_path, &joint, "_cut");
  if (joint_json.is_null()) {
    out << "  calib rig failed on the cut drive (see " << o.work << "/calib_rig_" << rig.kindName()
        << "_cut.txt)\n";
    return;
  }
  out << "  calib rig on the plan's drive cut to " << std::setprecision(0) << o.mounting_circle_s
      << " s: " << std::setprecision(1) << joint.wall_s << " s wall, " << joint.cpu_s << " CPU s\n";
  const std::string log_path = o.work + "/calib_mounting_circle.lcmlog";
  std::vector<std::string> sim_args = setArguments(kExactOdometry);
  appendSetArguments(&sim_args, {"sim.duration_s=" + std::to_string(o.mounting_circle_s)});
  if (!simulateLog(o, rig, sim_args, log_path, out)) return;
  const auto& config = std::get<MobileLidarConfig>(rig.config);
  const MobileLog log = loadMobileLog(log_path, config);
  const LidarMounting initial = config.mounting.toMounting();
  out << "  calib mounting (one parameter: gamma, beta, alpha), point to plane, EKF track, "
      << std::setprecision(0) << o.mounting_circle_s << " s circle with exact odometry ("
      << log.scans.size() << " scans), in this process:\n";
  const MountingRun today = runMounting(log, initial, false);
  const MountingRun old = runMounting(log, initial, true);
  for (const auto& [name, m] : {std::pair<const char*, const MountingRun&>{"today", today},
                                {"before issue 23 (reference solver)", old}}) {
    out << "    " << name << ": " << std::setprecision(1) << m.wall_s << " s wall, " << m.cpu_s
        << " CPU s; error gamma, beta, alpha " << mrad(m.error_mrad)
        << (m.ok ? "" : " (not calibrated)") << "\n";
  }
  const std::optional<Eigen::Vector3d> joint_error = mountingError(joint_json);
  out << "  calib rig's mounting against the old calib mounting, both on " << std::setprecision(0)
      << o.mounting_circle_s << " s of driving: " << std::setprecision(1)
      << old.wall_s / joint.wall_s << "x wall, " << old.cpu_s / joint.cpu_s
      << "x CPU (all of calib rig timed: wheels, lever arm, clock, room too); errors "
      << (joint_error ? mrad(*joint_error) : std::string("n/a")) << " against "
      << mrad(old.error_mrad) << "\n";
  out << "  today's calib mounting against the old: " << old.wall_s / today.wall_s << "x wall, "
      << old.cpu_s / today.cpu_s << "x CPU\n"
      << std::setprecision(2);
}

}  // namespace

int benchCalibration(const CalibrationBenchOptions& o, const Rig& rig, std::ostream& out) {
  std::filesystem::create_directories(o.work);
  const RigKind kind = rig.kind();
  const std::string log = o.work + "/calib_plan_" + rig.kindName() + ".lcmlog";
  out << "calib rig on calib plan's recording (sweepmap sim --rig " << rig.path << " "
      << calibrationRecordingSimLine(kind) << "), every build error at its default; the "
      << "command's wall time, CPU time (all threads) and peak RSS:\n";
  if (!simulateLog(o, rig, calibrationRecordingSimArgs(kind), log, out)) return 0;
  ChildRun run;
  const json r = calibRig(o, rig, log, &run);
  if (r.is_null()) {
    out << "  calib rig failed (see " << o.work << "/calib_rig_" << rig.kindName() << ".txt)\n";
    return 0;
  }
  out << "  " << std::setprecision(1) << run.wall_s << " s wall, " << run.cpu_s
      << " CPU s, peak RSS " << run.peak_kib / 1024.0 << " MiB; errors against the truth:\n";
  printErrors(r, out);
  out << std::setprecision(2);
  if (kind == RigKind::kMobileLidar) benchOldMounting(o, rig, out);
  return 0;
}

}  // namespace sweepmap
