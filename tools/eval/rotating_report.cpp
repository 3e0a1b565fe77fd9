#include "tools/eval/rotating_report.hpp"

#include <nlohmann/json.hpp>
#include <sstream>

#include "core/angles.hpp"
#include "core/atomic_file.hpp"
#include "tools/eval/common.hpp"
#include "tools/eval/rotating_figures.hpp"

namespace sweepmap::eval {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// --- report.json ------------------------------------------------------------------------

// The simulated error model (every sim.* key) and the keys that shape the experiment.
json simSettingsJson(const RotatingLidarConfig& rig) {
  const SimRigConfig& sim = rig.sim;
  return {{"sim.alpha_true_deg", sim.alpha_true_deg},
          {"sim.lidar_offset_x_mm", sim.lidar_offset_x_mm},
          {"sim.range_noise_sigma_mm", sim.range_noise_sigma_mm},
          {"sim.accel_jitter", sim.accel_jitter},
          {"sim.start_delay_max_ms", sim.start_delay_max_ms},
          {"sim.switch_response_ms", sim.switch_response_ms},
          {"sim.switch_response_jitter_ms", sim.switch_response_jitter_ms},
          {"sim.switch_hysteresis_deg", sim.switch_hysteresis_deg},
          {"sim.lidar_latency_ms", sim.lidar_latency_ms},
          {"motor.accel_deg_s2", rig.motor.accel_deg_s2},
          {"motor.margin_s", rig.motor.margin_s},
          {"motor.rehome_every_sweep", rig.motor.rehome_every_sweep},
          {"plate.alpha_deg", rig.plate.alpha_deg},
          {"geometry.lidar_offset_x_mm", rig.geometry.lidar_offset_x_mm}};
}

json inputsJson(const ReportInputs& in) {
  if (!in.experiment) return {{"logs", in.logs}, {"rig", in.rig}, {"overrides", in.overrides}};
  const ExperimentInputs& e = *in.experiment;
  return {{"rig", in.rig},
          {"scene", e.scene},
          {"overrides", in.overrides},
          {"experiment",
           {{"name", "paper"},
            {"seed", e.seed},
            {"sweeps_per_mode", e.sweeps_per_mode},
            {"calib_sweeps", e.calib_sweeps},
            {"naive", e.naive},
            {"seeds", e.seeds},
            {"plate_calibration", "plate_calibration.yaml"},
            {"simulator", simSettingsJson(e.rig)}}}};
}

json settingsJson(const EvalSettings& s) {
  return {{"wall_band_m", s.band_m},
          {"wall_edge_trim_m", s.edge_trim_m},
          {"wall_refit_distance_m", kRefitDistanceM},
          {"wall_voxel_m", s.wall_voxel_m},
          {"histogram_bin_mm", s.histogram_bin_mm},
          {"map_error_limit_m", s.map_error_limit_m},
          {"max_range_m", s.max_range_m},
          {"d50_over", "sweeps the method corrected (uncorrected ones are counted)"}};
}

json logsJson(const std::vector<LogStatus>& logs) {
  json out = json::array();
  for (const auto& l : logs) {
    json lj = {{"path", l.path},
               {"role", l.role},
               {"sweeps", l.sweeps},
               {"events", l.events},
               {"seconds", roundTo(l.seconds, 6)}};
    if (l.error) lj["error"] = l.message;
    if (!l.skipped_channels.empty()) lj["skipped_channels"] = l.skipped_channels;
    if (!l.scene.empty()) lj["scene"] = l.scene;
    out.push_back(lj);
  }
  return out;
}

json phiStatsJson(const PhiStats& st) {
  if (st.sweeps == 0) return {{"sweeps", 0}, {"uncorrected_sweeps", st.uncorrected}};
  return {{"sweeps", st.sweeps},       {"uncorrected_sweeps", st.uncorrected},
          {"max", roundTo(st.max, 6)}, {"mean", roundTo(st.mean, 6)},
          {"min", roundTo(st.min, 6)}, {"max_abs", roundTo(st.max_abs, 6)}};
}

json deviationJson(const DeviationStats& d, const EvalSettings& s, size_t sweeps) {
  json j;
  j["points"] = d.count;
  // Bent walls (shape error) leave the band: fewer wall points per sweep.
  j["points_per_sweep"] = sweeps > 0 ? d.count / static_cast<int64_t>(sweeps) : 0;
  j["rms_mm"] = roundTo(d.rmsMm(), 6);
  j["share_within_40mm"] = roundTo(d.shareWithin(), 6);
  j["within_mm"] = s.within_mm;
  j["histogram"] = {{"bin_mm", d.bin_mm},
                    {"range_mm", d.range_mm},
                    {"counts", d.bins},
                    {"outside_range", d.outside_range}};
  return j;
}

json sweepJson(const SweepRecord& r) {
  json j;
  j["log"] = r.log;
  j["id"] = r.id;
  j["points"] = r.points;
  j["plate_points"] = r.plate_points;
  j["corrected"] = r.corrected;
  j["reason"] = r.reason;
  j["phi_offset_deg"] = roundTo(r.phi_offset_rad * kRadToDeg, 6);
  if (r.has_centroid) {
    j["corrected_centroid"] = r.corrected_centroid;
    j["reason_centroid"] = r.reason_centroid;
    j["phi_offset_centroid_deg"] = roundTo(r.phi_offset_centroid_rad * kRadToDeg, 6);
  }
  if (r.phi_true_rad) {
    j["phi_true_deg"] = roundTo(*r.phi_true_rad * kRadToDeg, 6);
    json e;
    for (Method m : {Method::kRayPlane, Method::kCentroid, Method::kUncorrected}) {
      if (const auto v = r.phiErrorRad(m)) e[methodKey(m)] = roundTo(*v * kRadToDeg, 6);
    }
    j["phi_error_deg"] = e;
  }
  j["walls"] = r.wall_normals.size();
  if (!r.walls_reason.empty()) j["walls_reason"] = r.walls_reason;
  j["wall_points"] = r.deviations.count;
  j["wall_rms_mm"] = roundTo(r.deviations.rmsMm(), 6);
  j["wall_share_within_40mm"] = roundTo(r.deviations.shareWithin(), 6);
  return j;
}

// d50 of the method's worst corrected sweep, as reported (rounded); none without one.
std::optional<double> reportedD50(const Group& g, Method m, const EvalSettings& s) {
  const PhiStats st = phiStats(g.sweeps, m);
  if (st.sweeps == 0) return std::nullopt;
  return roundTo(mapErrorDistance(st.max_abs * kDegToRad, s.map_error_limit_m, s.max_range_m), 6);
}

json numberOrNull(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }

json modeJson(const Group& g, const EvalSettings& s, bool has_truth) {
  json mj;
  mj["sweeps"] = json::array();
  for (const auto& r : g.sweeps) mj["sweeps"].push_back(sweepJson(r));
  if (has_truth) {
    json pe;
    for (Method m : {Method::kRayPlane, Method::kCentroid, Method::kUncorrected}) {
      pe[methodKey(m)] = phiStatsJson(phiStats(g.sweeps, m));
    }
    mj["phi_error_deg"] = pe;
    mj["d50_m"] = numberOrNull(reportedD50(g, Method::kRayPlane, s));
    mj["d50_m_centroid"] = numberOrNull(reportedD50(g, Method::kCentroid, s));
    mj["d50_m_uncorrected"] = numberOrNull(reportedD50(g, Method::kUncorrected, s));
  }
  mj["walls"] = deviationJson(g.deviations, s, g.sweeps.size());
  return mj;
}

// "modes" and, with the truth, d50 of every mode by method ("d50_m", "d50_m_centroid",
// "d50_m_uncorrected").
void addModes(const ReportInput& in, const EvalSettings& s, bool has_truth, json* j) {
  json modes = json::object(), d50 = json::object(), d50c = json::object(), d50u = json::object();
  for (const auto& [mode, g] : in.modes) {
    const std::string key = std::to_string(mode);
    modes[key] = modeJson(g, s, has_truth);
    if (has_truth) {
      d50[key] = modes[key]["d50_m"];
      d50c[key] = modes[key]["d50_m_centroid"];
      d50u[key] = modes[key]["d50_m_uncorrected"];
    }
  }
  (*j)["modes"] = modes;
  if (has_truth) {
    (*j)["d50_m"] = d50;
    (*j)["d50_m_centroid"] = d50c;
    (*j)["d50_m_uncorrected"] = d50u;
  }
}

json alphaJson(const AlphaCalibration& a) {
  json j;
  j["sweeps_used"] = a.sweeps_used;
  j["alpha0_deg"] = roundTo(a.alpha0_rad * kRadToDeg, 6);
  if (!a.done) {
    j["error"] = a.reason;
    return j;
  }
  j["alpha_deg"] = roundTo(a.lm.alpha_rad * kRadToDeg, 6);
  j["iterations"] = a.lm.iterations;
  j["final_cost"] = a.lm.final_cost;
  j["converged"] = a.lm.converged;
  j["stop_reason"] = a.lm.stop_reason;
  j["mean_e_atti_before"] = roundTo(a.e_atti_before, 6);
  j["mean_e_atti_after"] = roundTo(a.e_atti_after, 6);
  json h = json::array();
  for (const auto& it : a.lm.history) {
    h.push_back(
        {{"k", it.k}, {"alpha_deg", it.alpha_rad * kRadToDeg}, {"cost", it.cost}, {"mu", it.mu}});
  }
  j["history"] = h;
  return j;
}

// alpha_source, the calibrated alphas, their error against the truth and the LM runs.
void addAlpha(const ReportInput& in, json* j) {
  json& r = *j;
  r["alpha_source"] = in.alpha_source;
  if (in.alpha.done) r["alpha_deg"] = roundTo(in.alpha.lm.alpha_rad * kRadToDeg, 6);
  if (in.alpha_centroid.done)
    r["alpha_deg_centroid"] = roundTo(in.alpha_centroid.lm.alpha_rad * kRadToDeg, 6);
  if (in.alpha_true_rad) {
    r["alpha_true_deg"] = roundTo(*in.alpha_true_rad * kRadToDeg, 6);
    if (in.alpha.done)
      r["alpha_error_deg"] = roundTo((in.alpha.lm.alpha_rad - *in.alpha_true_rad) * kRadToDeg, 6);
    if (in.alpha_centroid.done) {
      r["alpha_error_deg_centroid"] =
          roundTo((in.alpha_centroid.lm.alpha_rad - *in.alpha_true_rad) * kRadToDeg, 6);
    }
  }
  r["alpha_calibration"] = {{"ray_plane", alphaJson(in.alpha)},
                            {"centroid", alphaJson(in.alpha_centroid)},
                            {"applied_to_evaluation", in.alpha_applied}};
  if (in.alpha_applied) {
    r["alpha_calibration"]["evaluated_with_alpha_deg"] = {
        {"ray_plane", roundTo(in.alpha_eval_deg, 6)},
        {"centroid", roundTo(in.alpha_eval_centroid_deg, 6)}};
  }
}

// The naive sequence's mode-1 walls beside the improved sequence's (Fig. 1).
json shapeJson(const Group& naive, const std::map<int, Group>& modes, const EvalSettings& s) {
  json sh;
  sh["naive"] = deviationJson(naive.deviations, s, naive.sweeps.size());
  sh["naive"]["sweeps"] = json::array();
  for (const auto& r : naive.sweeps) sh["naive"]["sweeps"].push_back(sweepJson(r));
  const auto improved = modes.find(1);
  if (improved != modes.end())
    sh["improved"] = deviationJson(improved->second.deviations, s, improved->second.sweeps.size());
  sh["naive_rms_mm"] = roundTo(naive.deviations.rmsMm(), 6);
  sh["naive_share_within_40mm"] = roundTo(naive.deviations.shareWithin(), 6);
  if (improved != modes.end()) {
    sh["improved_rms_mm"] = roundTo(improved->second.deviations.rmsMm(), 6);
    sh["improved_share_within_40mm"] = roundTo(improved->second.deviations.shareWithin(), 6);
  }
  return sh;
}

json reportJson(const ReportInput& in, const EvalSettings& s, bool has_truth,
                const Figures& figures, const EvalRotatingResult& result) {
  json j;
  j["tool"] = "sweepmap eval (rotating_lidar)";
  j["inputs"] = inputsJson(in.inputs);
  j["sweeps"] = result.sweeps;
  j["settings"] = settingsJson(s);
  j["logs"] = logsJson(in.logs);
  addModes(in, s, has_truth, &j);
  addAlpha(in, &j);
  if (in.naive) j["shape"] = shapeJson(*in.naive, in.modes, s);
  j["figures"] = json::array();
  for (const auto& f : figures.files()) j["figures"].push_back(f.file);
  if (!figures.errors().empty()) j["figure_errors"] = figures.errors();
  j["timings_s"] = in.timings_s;
  if (result.failed) j["error"] = result.message;
  return j;
}

// --- report.md --------------------------------------------------------------------------

std::string optFixed(const std::optional<double>& v, int digits) {
  return v ? fixed(*v, digits) : "–";
}

int64_t perSweep(const Group& g) {
  return g.sweeps.empty() ? 0 : g.deviations.count / static_cast<int64_t>(g.sweeps.size());
}

void markdownHeader(const ReportInput& in, const EvalRotatingResult& result, std::ostream& md) {
  md << "# Rig A evaluation (Yuan 2021, section 5 and Appendix B)\n\n";
  md << "Made by `sweepmap eval (rotating_lidar)`. " << result.sweeps << " sweeps in "
     << in.modes.size() << " modes. Numbers in `report.json`.\n\n";
  if (result.failed) md << "**Error:** " << result.message << "\n\n";
  if (in.inputs.experiment) {
    const ExperimentInputs& e = *in.inputs.experiment;
    // The seed printed as an int (it was read back from report.json as one): a seed above
    // INT_MAX is printed wrapped, as it always was.
    md << "Simulated paper experiment: " << e.sweeps_per_mode << " sweeps per mode, "
       << e.calib_sweeps << " mode-7 sweeps for alpha, base seed " << static_cast<int>(e.seed)
       << ", logs in `logs/`.\n\n";
  }
}

void markdownAlpha(const ReportInput& in, std::ostream& md) {
  if (!in.alpha.done) {
    md << "- alpha not calibrated: " << in.alpha.reason << "\n";
    return;
  }
  md << "- alpha (calibrated, " << in.alpha_source
     << "): " << fixed(in.alpha.lm.alpha_rad * kRadToDeg, 4) << " deg with beta by ray_plane";
  if (in.alpha_centroid.done) {
    md << ", " << fixed(in.alpha_centroid.lm.alpha_rad * kRadToDeg, 4) << " deg by centroid";
  }
  if (in.alpha_true_rad) {
    md << "; true " << fixed(*in.alpha_true_rad * kRadToDeg, 4) << " deg (error "
       << fixed((in.alpha.lm.alpha_rad - *in.alpha_true_rad) * kRadToDeg, 4) << " deg)";
  }
  md << "; LM: " << in.alpha.lm.iterations << " iterations, " << in.alpha.lm.stop_reason << ", "
     << in.alpha.sweeps_used << " sweeps.\n";
  md << (in.alpha_applied ? "- The mode logs were evaluated with the calibrated alpha of each "
                            "method.\n"
                          : "- The logs were evaluated with the rig's alpha (plate.alpha_deg = " +
                                fixed(in.alpha_eval_deg, 4) + " deg), not the calibrated one.\n");
}

void markdownShape(const ReportInput& in, const EvalSettings& s, std::ostream& md) {
  if (!in.naive) return;
  const auto improved = in.modes.find(1);
  md << "- Shape (mode 1 walls): naive sequence RMS " << fixed(in.naive->deviations.rmsMm(), 1)
     << " mm, " << fixed(100 * in.naive->deviations.shareWithin(), 2) << " % within +-40 mm, "
     << perSweep(*in.naive) << " wall points per sweep";
  if (improved != in.modes.end()) {
    md << "; improved RMS " << fixed(improved->second.deviations.rmsMm(), 1) << " mm, "
       << fixed(100 * improved->second.deviations.shareWithin(), 2) << " %, "
       << perSweep(improved->second) << " wall points per sweep (bent walls leave the "
       << fixed(1000 * s.band_m, 0) << " mm band)";
  }
  md << ".\n";
}

void markdownModeTable(const ReportInput& in, const EvalSettings& s, bool has_truth,
                       std::ostream& md) {
  md << "\n| mode | sweeps | phi_error uncorrected min / mean / max (deg) | max abs(phi_error) "
        "ray_plane / centroid (deg) | d50 ray_plane (m) | d50 centroid (m) | d50 uncorrected (m) "
        "| wall RMS (mm) | within +-40 mm |\n";
  md << "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const auto& [mode, g] : in.modes) {
    md << "| " << mode << " | " << g.sweeps.size() << " | ";
    if (has_truth) {
      const PhiStats u = phiStats(g.sweeps, Method::kUncorrected);
      const PhiStats r = phiStats(g.sweeps, Method::kRayPlane);
      const PhiStats c = phiStats(g.sweeps, Method::kCentroid);
      md << fixed(u.min, 3) << " / " << fixed(u.mean, 3) << " / " << fixed(u.max, 3) << " | "
         << (r.sweeps ? fixed(r.max_abs, 4) : "–") << " / "
         << (c.sweeps ? fixed(c.max_abs, 4) : "–") << " | "
         << optFixed(reportedD50(g, Method::kRayPlane, s), 3) << " | "
         << optFixed(reportedD50(g, Method::kCentroid, s), 3) << " | "
         << optFixed(reportedD50(g, Method::kUncorrected, s), 3) << " | ";
    } else {
      md << "no truth | – | – | – | – | ";
    }
    md << fixed(g.deviations.rmsMm(), 1) << " | " << fixed(100 * g.deviations.shareWithin(), 2)
       << " % |\n";
  }
}

void markdownNotes(const EvalSettings& s, std::ostream& md) {
  md << "\nd50: the distance at which the worst corrected sweep's mapping error "
        "|E_map| = d tan|phi_error| (Eq. 21) reaches "
     << fixed(1000 * s.map_error_limit_m, 0) << " mm, capped at " << fixed(s.max_range_m, 0)
     << " m (paper: 2.2996 m in mode 1, 10 m in mode 7). Wall deviations: points within "
     << fixed(1000 * s.band_m, 0) << " mm of the four walls' planes (refit within "
     << fixed(1000 * kRefitDistanceM, 0) << " mm), " << fixed(1000 * s.edge_trim_m, 0)
     << " mm off their edges and corners.\n\n";
}

void markdownFigures(const Figures& figures, std::ostream& md) {
  md << "## Figures\n\n";
  for (const auto& f : figures.files()) {
    md << "![" << f.file << "](" << f.file << ")\n\n" << f.caption << "\n\n";
  }
  if (!figures.errors().empty()) {
    md << "Figures not drawn:\n\n";
    for (const auto& e : figures.errors()) md << "- " << e << "\n";
  }
}

std::string reportMarkdown(const ReportInput& in, const EvalSettings& s, bool has_truth,
                           const Figures& figures, const EvalRotatingResult& result) {
  std::ostringstream md;
  markdownHeader(in, result, md);
  md << "## Key numbers\n\n";
  markdownAlpha(in, md);
  markdownShape(in, s, md);
  markdownModeTable(in, s, has_truth, md);
  markdownNotes(s, md);
  markdownFigures(figures, md);
  return md.str();
}

// --- the result -------------------------------------------------------------------------

// Failed: the first log with a read error, else no sweep at all (with the channels seen).
void noteFailure(const ReportInput& in, EvalRotatingResult* result) {
  for (const auto& l : in.logs) {
    if (l.error) {
      result->failed = true;
      result->message = l.path + ": " + l.message;
      return;
    }
  }
  if (result->sweeps > 0) return;
  std::string seen;
  for (const auto& l : in.logs) {
    for (const auto& [channel, n] : l.skipped_channels)
      seen += (seen.empty() ? "" : ", ") + channel;
  }
  result->failed = true;
  result->message =
      "no sweeps in the logs: rig A's assembler needs LIDAR_SCAN and SCAN_WINDOW "
      "(channels found: " +
      (seen.empty() ? std::string("none") : seen) + ")";
}

}  // namespace

EvalRotatingResult writeReport(const fs::path& out, const ReportInput& in, const EvalSettings& s) {
  EvalRotatingResult result;
  bool has_truth = false;
  for (const auto& [mode, g] : in.modes) {
    result.sweeps += static_cast<int>(g.sweeps.size());
    for (const auto& r : g.sweeps) has_truth = has_truth || r.phi_true_rad.has_value();
  }
  Figures figures(out, s.plots);
  drawFigures(in, s, has_truth, &figures);
  for (const auto& f : figures.files()) result.figures.push_back(f.file);
  noteFailure(in, &result);
  writeFileAtomic((out / "report.json").string(),
                  reportJson(in, s, has_truth, figures, result).dump(2) + "\n");
  writeFileAtomic((out / "report.md").string(), reportMarkdown(in, s, has_truth, figures, result));
  return result;
}

}  // namespace sweepmap::eval
