#include "tools/eval/mobile_report.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/angles.hpp"
#include "core/atomic_file.hpp"

namespace sweepmap::eval {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

json nullable(const std::optional<double>& v) { return v ? json(roundTo(*v, 6)) : json(nullptr); }

std::optional<double> times1000(const std::optional<double>& v) {
  return v ? std::optional<double>(1000.0 * *v) : std::nullopt;
}

json vectorJson(const Eigen::Vector3d& v) {
  return {roundTo(v.x(), 6), roundTo(v.y(), 6), roundTo(v.z(), 6)};
}

json mountingJson(const LidarMounting& m) {
  return {{"gamma_rad", roundTo(m.gamma_rad, 6)},
          {"beta_rad", roundTo(m.beta_rad, 6)},
          {"alpha_rad", roundTo(m.alpha_rad, 6)}};
}

json planeJson(const WallPlaneFit& p, const std::vector<Eigen::Vector3f>& cloud) {
  const Eigen::Vector3d c = inlierCentroid(cloud, p.inlier_indices);
  return {
      {"normal", {roundTo(p.normal.x(), 6), roundTo(p.normal.y(), 6), roundTo(p.normal.z(), 6)}},
      {"offset_m", roundTo(p.offset, 6)},
      {"centroid_m", {roundTo(c.x(), 6), roundTo(c.y(), 6), roundTo(c.z(), 6)}},
      {"inliers", p.inliers},
      {"rms_mm", roundTo(1000.0 * p.rms_m, 6)}};
}

json dimsJson(const RoomDims& d) {
  return {{"L1", nullable(d.L1)}, {"L2", nullable(d.L2)}, {"L3", nullable(d.L3)}};
}

json deviationJson(const DeviationStats& d) {
  return {{"points", d.count},
          {"rms_mm", roundTo(d.rmsMm(), 6)},
          {"share_within_10mm", roundTo(d.shareWithin(), 6)},
          {"histogram", {{"bin_mm", d.bin_mm}, {"range_mm", d.range_mm}, {"counts", d.bins}}}};
}

json roomDeviationsJson(const RoomMeasures& m) {
  return {{"ceiling", deviationJson(m.ceiling)}, {"walls", deviationJson(m.walls)}};
}

// --- the circle's calibration (paper experiment) ---------------------------------------------

json doubleWallsJson(const DoubleWalls& g) {
  json jg = {{"max_mm", g.max_m ? json(roundTo(1000.0 * *g.max_m, 6)) : json(nullptr)},
             {"walls_mm", json::array()}};
  for (double d : g.wall_distance_m) jg["walls_mm"].push_back(roundTo(1000.0 * d, 6));
  if (!g.reason.empty()) jg["reason"] = g.reason;
  return jg;
}

json calibrationJson(const CircleCalibration& c) {
  json calibration = {{"log", "logs/circle.lcmlog"},
                      {"ours", json::parse(mountingResultJsonText(c.ours, c.truth))},
                      {"paper", json::parse(mountingResultJsonText(c.paper, c.truth))}};
  if (c.truth) calibration["truth"] = mountingJson(*c.truth);
  if (!c.double_walls.empty()) {
    json ghost;
    for (const auto& [name, walls] : c.double_walls) ghost[name] = doubleWallsJson(walls);
    calibration["circle_double_wall_mm"] = ghost;
  }
  return calibration;
}

// The error against the truth of a method's calibration (null without truth or result).
json calibrationError(const json& method, bool has_truth) {
  return has_truth && method.contains("error_mrad") ? method["error_mrad"] : json(nullptr);
}

// experiment, calibration and the calibrations' errors (mounting_error_mrad, ..._paper).
void addCircleCalibration(const CircleCalibration& c, json* r) {
  const json calibration = calibrationJson(c);
  (*r)["experiment"] = "paper";
  (*r)["calibration"] = calibration;
  (*r)["mounting_error_mrad"] = calibrationError(calibration["ours"], c.truth.has_value());
  (*r)["mounting_error_mrad_paper"] = calibrationError(calibration["paper"], c.truth.has_value());
}

// --- report.json ----------------------------------------------------------------------------

void addTrajectory(const MobileEvaluation& ev, json* r) {
  const TrajectoryErrors& e_odo = ev.odometry;
  const TrajectoryErrors& e_ekf = ev.ekf;
  (*r)["trajectory_rmse_m"] = {{"odometry", nullable(e_odo.rmse_m)},
                               {"ekf", nullable(e_ekf.rmse_m)}};
  (*r)["trajectory"] = {
      {"final_error_m", {{"odometry", nullable(e_odo.final_m)}, {"ekf", nullable(e_ekf.final_m)}}},
      {"max_error_m", {{"odometry", nullable(e_odo.max_m)}, {"ekf", nullable(e_ekf.max_m)}}},
      {"heading_rmse_mrad",
       {{"odometry", nullable(times1000(e_odo.heading_rmse_rad))},
        {"ekf", nullable(times1000(e_ekf.heading_rmse_rad))}}},
      {"wheel_readings_gated", ev.log.gated_wheel_readings},
      {"truth", ev.hasTruth()}};
  if (e_odo.rmse_m && e_ekf.rmse_m && *e_ekf.rmse_m > 0) {
    (*r)["trajectory"]["rmse_ratio_odometry_over_ekf"] = roundTo(*e_odo.rmse_m / *e_ekf.rmse_m, 6);
  }
}

// planes, ceiling_normal (and tilt), room_dims_m.
void addRoom(const MobileEvaluation& ev, json* r) {
  const RoomPlanes& planes = ev.room.planes;
  json jp;
  jp["walls"] = json::array();
  for (const auto& w : planes.walls) jp["walls"].push_back(planeJson(w, ev.cloud));
  jp["floor"] = planes.floor ? planeJson(*planes.floor, ev.cloud) : json(nullptr);
  jp["ceiling"] = planes.ceiling ? planeJson(*planes.ceiling, ev.cloud) : json(nullptr);
  if (!planes.reason.empty()) jp["reason"] = planes.reason;
  (*r)["planes"] = jp;
  if (ev.room.ceiling_up) {
    (*r)["ceiling_normal"] = vectorJson(*ev.room.ceiling_up);
    (*r)["ceiling_tilt_mrad"] =
        roundTo(1000.0 * std::acos(std::clamp(ev.room.ceiling_up->z(), -1.0, 1.0)), 6);
  } else {
    (*r)["ceiling_normal"] = nullptr;
  }
  (*r)["room_dims_m"] = dimsJson(ev.room.dims);
}

// The simulator's room and mounting, and the errors against them (null without truth).
void addTruth(const MobileEvaluation& ev, json* r) {
  if (!ev.log.truth_mounting) {
    (*r)["room_dims_error_mm"] = {{"L1", nullptr}, {"L2", nullptr}, {"L3", nullptr}};
    return;
  }
  const RoomDims& dims = ev.room.dims;
  const double* s = ev.log.truth_mounting->room_size_m;
  const double t1 = std::max(s[0], s[1]), t2 = std::min(s[0], s[1]), t3 = s[2];
  (*r)["room_dims_truth_m"] = {{"L1", t1}, {"L2", t2}, {"L3", t3}};
  const auto err = [](const std::optional<double>& v, double t) {
    return v ? json(roundTo(1000.0 * (*v - t), 6)) : json(nullptr);
  };
  (*r)["room_dims_error_mm"] = {
      {"L1", err(dims.L1, t1)}, {"L2", err(dims.L2, t2)}, {"L3", err(dims.L3, t3)}};
  const LidarMounting truth = trueMounting(*ev.log.truth_mounting);
  const LidarMounting& mounting = ev.mounting;
  (*r)["mounting_truth"] = mountingJson(truth);
  (*r)["mounting_used_error_mrad"] = {
      {"gamma", roundTo(1000.0 * (mounting.gamma_rad - truth.gamma_rad), 6)},
      {"beta", roundTo(1000.0 * (mounting.beta_rad - truth.beta_rad), 6)},
      {"alpha", roundTo(1000.0 * (mounting.alpha_rad - truth.alpha_rad), 6)}};
}

json beforeCalibrationJson(const LidarMounting& mounting, const RoomMeasures& rb) {
  json b;
  b["mounting"] = mountingJson(mounting);
  b["room_dims_m"] = dimsJson(rb.dims);
  b["deviations"] = roomDeviationsJson(rb);
  if (rb.ceiling_up) b["ceiling_normal"] = vectorJson(*rb.ceiling_up);
  return b;
}

void addLoopClosure(const LoopClosure& lc, json* r) {
  (*r)["ghost_mm"] = lc.ghost_m ? json(roundTo(1000.0 * *lc.ghost_m, 6)) : json(nullptr);
  json jl;
  jl["early_scans"] = lc.early.size();
  jl["late_scans"] = lc.late.size();
  jl["planes"] = json::array();
  for (const auto& p : lc.planes) {
    jl["planes"].push_back(
        {{"normal", {roundTo(p.normal.x(), 6), roundTo(p.normal.y(), 6), roundTo(p.normal.z(), 6)}},
         {"foot_m", {roundTo(p.foot_m.x(), 6), roundTo(p.foot_m.y(), 6), roundTo(p.foot_m.z(), 6)}},
         {"range_m", roundTo(p.range_m, 6)},
         {"early_points", p.early_points},
         {"late_points", p.late_points},
         {"distance_mm", roundTo(1000.0 * p.distance_m, 6)}});
  }
  if (!lc.reason.empty()) jl["reason"] = lc.reason;
  (*r)["loop_closure"] = jl;
}

json reportJson(const MobileEvaluation& ev, const CircleCalibration* circle,
                const std::vector<Figures::Entry>& figures,
                const std::vector<std::string>& figure_errors) {
  json r;
  r["log"] = ev.log_name;
  if (ev.log.log_error) r["log_error"] = ev.log.error;
  r["scans"] = ev.log.scans.size();
  r["invalid_scans"] = ev.log.invalid_scans;
  r["mounting"] = mountingJson(ev.mounting);
  r["pose_channel"] = ev.pose_channel;
  if (circle) addCircleCalibration(*circle, &r);
  addTrajectory(ev, &r);
  r["points"] = ev.cloud.size();
  addRoom(ev, &r);
  addTruth(ev, &r);
  // The mounting's error against the truth: the experiment reports its calibration's; a log
  // evaluated on its own reports the mounting it was assembled with.
  if (!circle) {
    r["mounting_error_mrad"] =
        r.contains("mounting_used_error_mrad") ? r["mounting_used_error_mrad"] : json(nullptr);
  }
  r["deviations"] = roomDeviationsJson(ev.room);
  if (ev.before) r["before_calibration"] = beforeCalibrationJson(*ev.before_mounting, *ev.before);
  r["density_D_m"] = roundTo(ev.density_m, 6);
  addLoopClosure(ev.loop, &r);
  r["figures"] = json::array();
  for (const auto& f : figures) r["figures"].push_back(f.file);
  if (!figure_errors.empty()) r["figure_errors"] = figure_errors;
  return r;
}

// --- report.md ------------------------------------------------------------------------------

// The key numbers of report.json, as it prints them.
std::string reportMarkdown(const json& r, const MobileEvaluation& ev,
                           const std::vector<Figures::Entry>& figures) {
  std::ostringstream md;
  md << "# Rig B evaluation: " << r["log"].get<std::string>() << "\n\n";
  md << "- scans " << ev.log.scans.size() << ", points " << ev.cloud.size() << ", poses from "
     << ev.pose_channel << "\n";
  md << "- trajectory RMSE: odometry " << r["trajectory_rmse_m"]["odometry"].dump() << " m, EKF "
     << r["trajectory_rmse_m"]["ekf"].dump() << " m\n";
  md << "- room dimensions L1, L2, L3: " << r["room_dims_m"].dump() << " m; error "
     << r["room_dims_error_mm"].dump() << " mm\n";
  md << "- ceiling normal " << r["ceiling_normal"].dump() << "; density D "
     << r["density_D_m"].dump() << " m; ghost where the loop closes " << r["ghost_mm"].dump()
     << " mm\n";
  md << "- mounting (gamma, beta, alpha) " << r["mounting"].dump() << "; error against the truth "
     << r["mounting_error_mrad"].dump() << " mrad\n";
  if (r.contains("calibration")) {
    const json& c = r["calibration"];
    md << "- calibration from the circle: ours "
       << c["ours"].value("error_mrad", json(nullptr)).dump() << " mrad (residual "
       << c["ours"]["residual_before_m"].dump() << " -> " << c["ours"]["residual_after_m"].dump()
       << " m), the paper's " << c["paper"].value("error_mrad", json(nullptr)).dump()
       << " mrad; circle double wall " << c["circle_double_wall_mm"]["before"]["max_mm"].dump()
       << " mm before, " << c["circle_double_wall_mm"]["after"]["max_mm"].dump() << " mm after\n";
  }
  md << "\n";
  for (const auto& f : figures)
    md << "![" << f.caption << "](" << f.file << ")\n\n" << f.caption << "\n\n";
  return md.str();
}

}  // namespace

void writeMobileReport(const fs::path& out, const MobileEvaluation& ev,
                       const CircleCalibration* circle, const std::vector<Figures::Entry>& figures,
                       const std::vector<std::string>& figure_errors) {
  const json r = reportJson(ev, circle, figures, figure_errors);
  writeFileAtomic((out / "report.json").string(), r.dump(2) + "\n");
  writeFileAtomic((out / "report.md").string(), reportMarkdown(r, ev, figures));
}

void writeCalibrationFailureReport(const fs::path& out, const CircleCalibration& circle) {
  const json r = {{"experiment", "paper"}, {"calibration", calibrationJson(circle)}};
  writeFileAtomic((out / "report.json").string(), r.dump(2) + "\n");
}

}  // namespace sweepmap::eval
