#include "tools/eval/eval_profile_report.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/angles.hpp"
#include "core/atomic_file.hpp"
#include "tools/eval/common.hpp"

namespace sweepmap::eval {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
// The bound for ours and the paper's own (Zhao 2021 section 4).
constexpr double kOursBoundPct = 0.1;
constexpr double kPaperBoundPct = 0.25;

// Zhao 2021 Table 2 as printed: CMM size, then value [mm] and error [%] at M/N = 123/409,
// 110/395 and 130/425. Three printed percentages disagree with their values (right diameter
// at 130/425: +0.30 % for 51.53 mm; rectangle length at 123/409: -0.05 % for 40.01 mm;
// rectangle depth at 130/425: 0.80 % for 19.85 mm); they are kept as printed.
struct PaperRow {
  double cmm, v[3], pct[3];
};
const PaperRow kPaperTable2[kPieceFeatureCount] = {
    {50.01, {49.97, 47.24, 51.58}, {-0.08, -5.54, 3.14}},
    {30.03, {29.96, 29.94, 29.86}, {-0.23, -0.30, -0.57}},
    {50.02, {49.96, 47.30, 51.53}, {-0.12, -5.32, 0.30}},
    {30.02, {29.96, 29.91, 29.85}, {-0.20, -0.37, -0.57}},
    {39.99, {40.01, 38.01, 41.17}, {-0.05, -4.95, 2.95}},
    {80.03, {80.01, 79.99, 80.01}, {-0.02, -0.05, -0.02}},
    {20.01, {19.99, 19.86, 19.85}, {-0.10, -0.75, 0.80}}};
const char* const kPaperColumns[3] = {"M_123_N_409", "M_110_N_395", "M_130_N_425"};
// Features along the scanning direction (the turntable's motion): their size scales with the
// distance from the axis, so wrong M, N change them. The round grooves' diameters are partly
// along it (a cylinder fit averages the directions).
const bool kAlongScan[kPieceFeatureCount] = {true, false, true, false, true, false, false};

json orNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

const ProfileSetting* find(const ProfileEvaluation& ev, const std::string& name) {
  for (const auto& s : ev.settings) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

json calibrationJson(const ProfileEvaluation& ev) {
  const AxisOffsetResult& r = ev.ours;
  json planes = json::array();
  for (size_t k = 0; k < r.planes.size(); ++k) {
    planes.push_back({{"points", ev.plate_points[k]},
                      {"points_used", ev.plate_points_used[k]},
                      {"rms_mm", r.planes[k].rms_mm}});
  }
  return {{"ours",
           {{"m_mm", r.geometry.m_mm},
            {"n_mm", r.geometry.n_mm},
            {"laser_tilt_deg", r.geometry.laser_tilt_rad * kRadToDeg},
            {"sigma_m_mm", orNull(r.sigma_m_mm)},
            {"sigma_n_mm", orNull(r.sigma_n_mm)},
            {"sigma_laser_tilt_deg", orNull(r.sigma_tilt_deg)},
            {"observable", r.observable},
            {"iterations", r.iterations},
            {"rms_before_mm", r.rms_before_mm},
            {"rms_after_mm", r.rms_after_mm},
            {"warnings", r.warnings}}},
          {"grid",
           {{"m_mm", ev.grid.m_mm},
            {"n_mm", ev.grid.n_mm},
            {"s_min_mm", ev.grid.s_min_mm},
            {"step_mm", ev.grid_options.step_mm},
            {"m_interval_mm", {ev.grid_options.m_min_mm, ev.grid_options.m_max_mm}},
            {"n_interval_mm", {ev.grid_options.n_min_mm, ev.grid_options.n_max_mm}},
            {"evaluations", ev.grid.s_mm.size()}}},
          {"nominal_m_mm", ev.nominal.m_mm},
          {"nominal_n_mm", ev.nominal.n_mm},
          {"plates", planes}};
}

json settingsJson(const ProfileEvaluation& ev) {
  json j;
  for (const auto& s : ev.settings) {
    json sizes = json::object();
    for (int k = 0; k < kPieceFeatureCount; ++k) {
      json v = json::array();
      for (const auto& scan : s.sizes_mm) v.push_back(orNull(scan[k]));
      sizes[kPieceFeatures[k]] = v;
    }
    j[s.name] = {{"label", s.label},
                 {"m_mm", s.geometry.m_mm},
                 {"n_mm", s.geometry.n_mm},
                 {"laser_tilt_deg", s.geometry.laser_tilt_rad * kRadToDeg},
                 {"encoder_zero_deg", s.geometry.encoder_zero_rad * kRadToDeg},
                 {"sizes_mm", sizes},
                 {"problems", s.problems}};
  }
  return j;
}

json featureErrorJson(const ProfileEvaluation& ev) {
  json j;
  for (const auto& s : ev.settings) {
    for (int k = 0; k < kPieceFeatureCount; ++k) {
      const Stats st = errorPctStats(s, ev.piece, k);
      j[s.name][kPieceFeatures[k]] = {
          {"mean", orNull(st.mean)}, {"std", orNull(st.std)}, {"count", st.count}};
    }
  }
  return j;
}

json paperJson() {
  json j;
  for (int k = 0; k < kPieceFeatureCount; ++k) {
    json row = {{"cmm_mm", kPaperTable2[k].cmm}};
    for (int c = 0; c < 3; ++c) {
      row[kPaperColumns[c]] = {{"mm", kPaperTable2[k].v[c]}, {"error_pct", kPaperTable2[k].pct[c]}};
    }
    j[kPieceFeatures[k]] = row;
  }
  return j;
}

// The statements the experiment must show, measured.
json checksJson(const ProfileEvaluation& ev) {
  const ProfileSetting *ours = find(ev, "ours"), *small = find(ev, "too_small"),
                       *large = find(ev, "too_large");
  json along = json::array();
  bool shrink = true, grow = true;
  for (int k = 0; k < kPieceFeatureCount; ++k) {
    if (!kAlongScan[k]) continue;
    along.push_back(kPieceFeatures[k]);
    const double o = errorPctStats(*ours, ev.piece, k).mean;
    shrink = shrink && errorPctStats(*small, ev.piece, k).mean < o;
    grow = grow && errorPctStats(*large, ev.piece, k).mean > o;
  }
  double worst = 0.0;
  for (int k = 0; k < kPieceFeatureCount; ++k) {
    worst = std::max(worst, std::fabs(errorPctStats(*ours, ev.piece, k).mean));
  }
  return {{"ours_bound_pct", kOursBoundPct},
          {"paper_bound_pct", kPaperBoundPct},
          {"ours_worst_mean_error_pct", worst},
          {"ours_within_bound", withinPct(ev, *ours, kOursBoundPct)},
          {"along_scan_features", along},
          {"along_scan_shrink_when_too_small", shrink},
          {"along_scan_grow_when_too_large", grow}};
}

// The simulated sensor beside the datasheet values config/rig_c.yaml cites for the
// Gocator 2340 (clearance 190 mm, range 210 mm, FOV 96-194 mm, 1280 points, X resolution
// 0.075-0.150 mm, Z resolution 0.013-0.037 mm, 170 Hz full window).
json sensorJson(const ProfileEvaluation& ev) {
  const ProfilerConfig& p = ev.profiler;
  const double half = p.fanHalfAngleRad();
  const double fov_near = 2 * p.near_mm * std::tan(half);
  const double step_deg = ev.turntable.speed_deg_s / p.profile_rate_hz;
  const double radius = std::hypot(ev.truth.m_mm, ev.truth.n_mm);
  return {{"model", "LMI Gocator 2340 class (config/rig_c.yaml)"},
          {"column_count", p.column_count},
          {"near_mm", p.near_mm},
          {"far_mm", p.far_mm},
          {"fov_far_mm", p.fov_far_mm},
          {"fov_near_mm_single_apex_fan", fov_near},
          {"datasheet_fov_near_mm", 96.0},
          {"x_spacing_near_mm", fov_near / (p.column_count - 1)},
          {"x_spacing_far_mm", p.fov_far_mm / (p.column_count - 1)},
          {"profile_rate_hz", p.profile_rate_hz},
          {"range_noise_sigma_mm", ev.range_noise_sigma_mm},
          {"encoder_counts_per_revolution", ev.turntable.counts_per_revolution},
          {"encoder_noise_counts", ev.encoder_noise_counts},
          {"scan_step_deg", step_deg},
          {"scan_step_at_sensor_radius_mm", radius * step_deg * M_PI / 180.0}};
}

json reportJson(const ProfileEvaluation& ev, const std::vector<Figures::Entry>& figures,
                const std::vector<std::string>& figure_errors) {
  json r;
  r["experiment"] = "paper";
  r["paper"] = "Zhao 2021 (Sensors 21, 8359) Tables 1-2";
  r["rig"] = ev.rig_path;
  r["seed"] = ev.seed;
  r["repeats"] = ev.repeats;
  r["logs"] = ev.logs;
  r["truth"] = {{"m_mm", ev.truth.m_mm},
                {"n_mm", ev.truth.n_mm},
                {"laser_tilt_deg", ev.truth.laser_tilt_rad * kRadToDeg},
                {"encoder_zero_deg", ev.truth.encoder_zero_rad * kRadToDeg}};
  r["calibration"] = calibrationJson(ev);
  r["offset_error_mm"] = {
      {"ours",
       {{"M", ev.ours.geometry.m_mm - ev.truth.m_mm},
        {"N", ev.ours.geometry.n_mm - ev.truth.n_mm}}},
      {"grid", {{"M", ev.grid.m_mm - ev.truth.m_mm}, {"N", ev.grid.n_mm - ev.truth.n_mm}}}};
  json truth_sizes;
  for (int k = 0; k < kPieceFeatureCount; ++k)
    truth_sizes[kPieceFeatures[k]] = trueSize(ev.piece, k);
  r["feature_truth_mm"] = truth_sizes;
  r["settings"] = settingsJson(ev);
  r["feature_error_pct"] = featureErrorJson(ev);
  r["paper_table2"] = paperJson();
  r["checks"] = checksJson(ev);
  r["sensor"] = sensorJson(ev);
  r["timings_s"] = {{"ours", ev.ours.seconds}, {"grid", ev.grid.seconds}};
  r["figures"] = json::array();
  for (const auto& f : figures) r["figures"].push_back(f.file);
  r["figure_errors"] = figure_errors;
  return r;
}

// --- report.md --------------------------------------------------------------------------

std::string cell(const Stats& st, double truth) {
  if (st.count == 0) return "n/a";
  return fixed(truth * (1 + st.mean / 100), 3) + " mm, " + (st.mean >= 0 ? "+" : "") +
         fixed(st.mean, 3) + " ± " + fixed(st.std, 3) + " %";
}

std::string reportMarkdown(const ProfileEvaluation& ev, const json& r,
                           const std::vector<Figures::Entry>& figures) {
  std::ostringstream m;
  m << "# Rig C: Zhao 2021 Table 2, simulated\n\n"
    << "Rig `" << ev.rig_path << "`, seed " << ev.seed << ", " << ev.repeats
    << " test-piece scans per setting. Command: `sweepmap eval --experiment paper --rig rig_c"
    << " --out DIR --seed " << ev.seed << "`.\n\n## Calibration (Table 1)\n\n"
    << "| | M [mm] | N [mm] | error M, N [mm] | time [s] |\n|---|---|---|---|---|\n"
    << "| truth | " << fixed(ev.truth.m_mm, 3) << " | " << fixed(ev.truth.n_mm, 3) << " | | |\n"
    << "| ours (Ceres, with the laser tilt) | " << fixed(ev.ours.geometry.m_mm, 3) << " ± "
    << fixed(ev.ours.sigma_m_mm, 3) << " | " << fixed(ev.ours.geometry.n_mm, 3) << " ± "
    << fixed(ev.ours.sigma_n_mm, 3) << " | "
    << fixed(r["offset_error_mm"]["ours"]["M"].get<double>(), 3) << ", "
    << fixed(r["offset_error_mm"]["ours"]["N"].get<double>(), 3) << " | "
    << fixed(ev.ours.seconds, 3) << " |\n"
    << "| paper's grid (1 mm, M " << ev.grid_options.m_min_mm << "-" << ev.grid_options.m_max_mm
    << ", N " << ev.grid_options.n_min_mm << "-" << ev.grid_options.n_max_mm << ") | "
    << fixed(ev.grid.m_mm, 0) << " | " << fixed(ev.grid.n_mm, 0) << " | "
    << fixed(r["offset_error_mm"]["grid"]["M"].get<double>(), 3) << ", "
    << fixed(r["offset_error_mm"]["grid"]["N"].get<double>(), 3) << " | "
    << fixed(ev.grid.seconds, 3) << " |\n\n"
    << "The laser tilt found by ours: " << fixed(ev.ours.geometry.laser_tilt_rad * kRadToDeg, 3)
    << " deg (truth " << fixed(ev.truth.laser_tilt_rad * kRadToDeg, 3)
    << " deg); the grid's model (Eq. 7) has none.\n\n## Test piece (Table 2)\n\n"
    << "Mean measured size and error (mean ± standard deviation over the scans) per setting; "
       "the truth is the simulator's (TRUTH_TEST_PIECE, Table 2's CMM sizes). The wrong "
       "settings are the truth's M, N moved as the paper's 110/395 and 130/425 are from its "
       "123/409.\n\n| feature | truth [mm] |";
  for (const auto& s : ev.settings) m << " " << s.label << " |";
  m << " paper 123/409 | paper 110/395 | paper 130/425 |\n|---|---|";
  for (size_t i = 0; i < ev.settings.size() + 3; ++i) m << "---|";
  m << "\n";
  for (int k = 0; k < kPieceFeatureCount; ++k) {
    const double t = trueSize(ev.piece, k);
    m << "| " << kPieceFeatures[k] << (kAlongScan[k] ? " (along scan)" : "") << " | " << fixed(t, 2)
      << " |";
    for (const auto& s : ev.settings) m << " " << cell(errorPctStats(s, ev.piece, k), t) << " |";
    for (int c = 0; c < 3; ++c) {
      m << " " << fixed(kPaperTable2[k].v[c], 2) << " mm, "
        << (kPaperTable2[k].pct[c] >= 0 ? "+" : "") << fixed(kPaperTable2[k].pct[c], 2) << " % |";
    }
    m << "\n";
  }
  const json& c = r["checks"];
  m << "\nOurs: worst |mean error| " << fixed(c["ours_worst_mean_error_pct"].get<double>(), 3)
    << " % (bound " << kOursBoundPct << " %, the paper's " << kPaperBoundPct
    << " %): " << (c["ours_within_bound"].get<bool>() ? "within" : "NOT within")
    << ". Along the scan, too-small M, N "
    << (c["along_scan_shrink_when_too_small"].get<bool>() ? "shrink" : "do NOT shrink")
    << " the sizes and too-large ones "
    << (c["along_scan_grow_when_too_large"].get<bool>() ? "grow" : "do NOT grow") << " them.\n";
  for (const auto& s : ev.settings) {
    for (const auto& p : s.problems) m << "\n- " << s.name << ": " << p;
  }
  const json& sn = r["sensor"];
  m << "\n## Simulated sensor\n\n"
    << "Gocator 2340 class: " << ev.profiler.column_count << " points per profile, "
    << ev.profiler.near_mm << "-" << ev.profiler.far_mm << " mm range, line "
    << fixed(sn["fov_near_mm_single_apex_fan"].get<double>(), 1) << "-" << ev.profiler.fov_far_mm
    << " mm (datasheet 96-194 mm; the simulator's fan has one apex, so its near line is "
       "shorter), point spacing "
    << fixed(sn["x_spacing_near_mm"].get<double>(), 3) << "-"
    << fixed(sn["x_spacing_far_mm"].get<double>(), 3) << " mm along the line (datasheet X "
    << "resolution 0.075-0.150 mm), range noise " << ev.range_noise_sigma_mm
    << " mm (datasheet Z resolution 0.013-0.037 mm), " << ev.profiler.profile_rate_hz << " Hz; at "
    << ev.turntable.speed_deg_s << " deg/s the profiles are "
    << fixed(sn["scan_step_deg"].get<double>(), 4) << " deg, "
    << fixed(sn["scan_step_at_sensor_radius_mm"].get<double>(), 2)
    << " mm apart along the scan.\n\n## Figures\n\n";
  for (const auto& f : figures)
    m << "![" << f.caption << "](" << f.file << ")\n\n" << f.caption << "\n\n";
  return m.str();
}

}  // namespace

double trueSize(const TestPieceConfig& p, int k) {
  const double v[kPieceFeatureCount] = {p.left_diameter_mm, p.left_depth_mm,  p.right_diameter_mm,
                                        p.right_depth_mm,   p.rect_length_mm, p.rect_width_mm,
                                        p.rect_depth_mm};
  return v[k];
}

Stats errorPctStats(const ProfileSetting& s, const TestPieceConfig& piece, int k) {
  Stats st;
  const double t = trueSize(piece, k);
  double sum = 0.0, sum2 = 0.0;
  for (const auto& scan : s.sizes_mm) {
    if (!std::isfinite(scan[k])) continue;
    const double e = (scan[k] - t) / t * 100.0;
    sum += e;
    ++st.count;
  }
  if (st.count == 0) {
    st.mean = st.std = std::numeric_limits<double>::quiet_NaN();
    return st;
  }
  st.mean = sum / st.count;
  for (const auto& scan : s.sizes_mm) {
    if (!std::isfinite(scan[k])) continue;
    const double e = (scan[k] - t) / t * 100.0 - st.mean;
    sum2 += e * e;
  }
  st.std = st.count > 1 ? std::sqrt(sum2 / (st.count - 1)) : 0.0;
  return st;
}

bool withinPct(const ProfileEvaluation& ev, const ProfileSetting& s, double limit_pct) {
  for (int k = 0; k < kPieceFeatureCount; ++k) {
    const Stats st = errorPctStats(s, ev.piece, k);
    if (st.count != static_cast<int>(s.sizes_mm.size()) || !(std::fabs(st.mean) <= limit_pct)) {
      return false;
    }
  }
  return true;
}

void writeProfileReport(const fs::path& dir, const ProfileEvaluation& ev,
                        const std::vector<Figures::Entry>& figures,
                        const std::vector<std::string>& figure_errors) {
  const json r = reportJson(ev, figures, figure_errors);
  writeFileAtomic((dir / "report.json").string(), r.dump(2) + "\n");
  writeFileAtomic((dir / "report.md").string(), reportMarkdown(ev, r, figures));
}

}  // namespace sweepmap::eval
