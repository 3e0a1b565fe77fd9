#include "tools/offline/replay.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "calib/rotating_geometry.hpp"
#include "core/angles.hpp"
#include "core/atomic_file.hpp"
#include "core/event_log.hpp"
#include "core/progress.hpp"
#include "mapping/cloud_io.hpp"
#include "mapping/occupancy_map.hpp"
#include "mapping/plot.hpp"
#include "processes/mapper_node.hpp"
#include "tools/offline/log_sweeps.hpp"
#include "tools/offline/views_3d.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

// The JSON line of one sweep in summary.json.
nlohmann::json sweepJson(const AssembledSweep& s, const SweepTruth& truth,
                         const std::string& file) {
  nlohmann::json j;
  j["id"] = s.window.sweep_id;
  j["file"] = file;
  j["window_start_utime"] = s.window.start_utime;
  j["mode"] = s.window.mode;
  j["scans"] = s.scans;
  j["missing_scans"] = s.missing_scans;
  j["points"] = s.points.size();
  j["plate_points"] = s.plate.points;
  j["beta_deg"] = s.plate.found ? nlohmann::json(roundTo(s.plate.beta_rad * kRadToDeg, 6))
                                : nlohmann::json(nullptr);
  j["phi_offset_deg"] = roundTo(s.phi_offset_rad * kRadToDeg, 6);
  j["corrected"] = s.corrected;
  j["reason"] = s.reason;
  if (truth.phi_true_rad) {
    // Frame O' is the lidar frame at the window's first ray: the true phi_offset is
    // the true shaft angle then (0 = X_L along the rig's front).
    j["phi_true_deg"] = roundTo(*truth.phi_true_rad * kRadToDeg, 6);
    j["phi_error_deg"] = roundTo(wrapAngle(s.phi_offset_rad - *truth.phi_true_rad) * kRadToDeg, 6);
  }
  return j;
}

void writeSummary(const fs::path& out, const std::string& log_path, const LogReadResult& read,
                  const nlohmann::json& sweeps, const MapperNode& mapper,
                  const ReplayResult& result, const RotatingLidarConfig& rig) {
  nlohmann::json summary;
  summary["log"] = fs::path(log_path).filename().string();
  summary["events"] = read.events;
  summary["sweeps"] = sweeps;
  const MapStats st = mapper.map().stats();
  summary["map"] = {{"resolution_m", st.resolution_m},
                    {"occupied_voxels", st.occupied_voxels},
                    {"free_voxels", st.free_voxels},
                    {"sweeps_inserted", st.sweeps_inserted}};
  summary["skipped_channels"] = read.skipped_channels;
  summary["assembler"] = {{"scans", read.scans},
                          {"invalid", read.invalid},
                          {"dropped", read.dropped},
                          {"sweeps_incomplete", read.sweeps_incomplete},
                          {"scans_missing", read.scans_missing},
                          {"windows_missing", read.windows_missing}};
  // What the assembler placed the points with (a calibration file's values if the rig names one).
  summary["geometry"] = {{"lidar_offset_x_mm", rig.geometry.lidar_offset_x_mm},
                         {"calibration_file", rig.geometry.calibration_file},
                         {"plate_alpha_deg", rig.plate.alpha_deg}};
  if (read.alpha_true_rad) {
    summary["truth"] = {
        {"alpha_true_deg", roundTo(*read.alpha_true_rad * kRadToDeg, 6)},
        {"lidar_offset_x_mm", read.lidar_offset_x_true_m
                                  ? nlohmann::json(*read.lidar_offset_x_true_m * 1e3)
                                  : nlohmann::json(nullptr)},
        {"scene", read.scene}};
  }
  if (result.log_error) summary["error"] = result.error;
  writeFileAtomic((out / "summary.json").string(), summary.dump(2) + "\n");
}

void plotFirstSweep(const fs::path& out, const std::vector<Eigen::Vector3f>& first_Op,
                    const std::vector<Eigen::Vector3f>& first_O) {
  PlotOptions po;
  po.title = "Sweep 0, top view (z between -0.3 and 1.0 m): uncorrected C_O' and corrected C_O";
  po.z_band_m = PlotRange{-0.3, 1.0};
  try {
    plotTopView((out / "top_view.png").string(),
                {{"uncorrected C_O'", "red", first_Op}, {"corrected C_O", "blue", first_O}}, po);
  } catch (const std::exception& e) {
    std::cerr << "replay: top view not drawn: " << e.what() << "\n";
  }
}

}  // namespace

ReplayResult replayLog(const ReplayOptions& options, const RotatingLidarConfig& rig) {
  ReplayResult result;
  const fs::path out(options.out_dir);
  if (!fs::exists(options.log_path)) throw std::runtime_error(options.log_path + ": no such log");
  fs::create_directories(out / "sweeps");

  EventLogWriter derived((out / "derived.lcmlog").string());
  MapperNode mapper(rig.mapper, (out / "map.bt").string());
  nlohmann::json sweeps = nlohmann::json::array();
  std::vector<Eigen::Vector3f> first_Op, first_O, all_O;
  ProgressOptions po;
  po.enabled = options.progress;
  Progress bar("replay", po);

  LogSweepOptions lo;
  lo.extra_nodes = {&mapper};
  lo.sink = [&](const Message& m) { derived.write(m.utime, m.channel, m.data); };
  lo.progress = [&](uint64_t offset, uint64_t size) {
    bar.update(size > 0 ? static_cast<double>(offset) / static_cast<double>(size) : -1.0);
  };
  const auto onSweep = [&](const AssembledSweep& s, const SweepTruth& truth) {
    std::ostringstream name;
    // Numbered in log order: sweep ids start again when the motor process restarts.
    name << "sweep_" << std::setw(6) << std::setfill('0') << result.sweeps;
    writePcdAndPly((out / "sweeps" / name.str()).string(), s.points, s.intensities);
    sweeps.push_back(sweepJson(s, truth, name.str()));
    result.points += static_cast<int64_t>(s.points.size());
    if (options.plots) all_O.insert(all_O.end(), s.points.begin(), s.points.end());
    if (++result.sweeps == 1) {
      first_Op = s.points_Op;
      first_O = s.points;
    }
  };
  const LogReadResult read = forEachSweep(options.log_path, rig, onSweep, lo);
  derived.close();
  result.events = read.events;
  result.sweeps_incomplete = static_cast<int>(read.sweeps_incomplete);
  result.scans_missing = read.scans_missing;
  result.windows_missing = read.windows_missing;
  result.log_error = read.log_error;
  result.error = read.error;
  result.log_duration_s = 1e-6 * static_cast<double>(read.last_utime - read.first_utime);
  writeSummary(out, options.log_path, read, sweeps, mapper, result, rig);
  if (options.plots && !first_O.empty()) {
    plotFirstSweep(out, first_Op, first_O);
    drawViews3d(out, "replay", "rig A replay, " + std::to_string(result.sweeps) + " sweeps", "O",
                all_O, mapper.map().occupiedCentres(), rig.mapper.resolution_m, true);
  }
  return result;
}

}  // namespace sweepmap
