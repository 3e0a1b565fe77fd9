#include "tools/offline/runs.hpp"
#include "tools/eval/eval_mobile.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "calib/cloud_density.hpp"
#include "calib/mounting_calibration.hpp"
#include "calib/rotating_geometry.hpp"
#include "calib/walls.hpp"
#include "core/calibration_file.hpp"
#include "core/event_log.hpp"
#include "drivers/scene.hpp"
#include "core/atomic_file.hpp"
#include "mapping/cloud_io.hpp"
#include "mapping/plot.hpp"
#include "tools/eval/metrics.hpp"
#include "tools/eval/figures.hpp"
#include "tools/offline/mobile_log.hpp"
#include "tools/offline/sim_mobile.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

double round6(double v) { return std::round(v * 1e6) / 1e6; }

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

json nullable(const std::optional<double>& v) { return v ? json(round6(*v)) : json(nullptr); }

// Position error of `estimate` against `truth` at each estimate's time.
struct TrajectoryErrors {
  std::vector<double> t_s, error_m, heading_error_rad;
  std::optional<double> rmse_m, final_m, max_m, heading_rmse_rad, heading_max_rad;
};

TrajectoryErrors trajectoryErrors(const PoseTrack& estimate, const PoseTrack& truth) {
  TrajectoryErrors e;
  if (estimate.size() == 0 || truth.size() == 0) return e;
  const int64_t t0 = truth.poses().begin()->first;
  double ss = 0, mx = 0, hs = 0, hm = 0;
  for (const auto& [utime, p] : estimate.poses()) {
    const auto t = truth.at(utime);
    if (!t) continue;
    const double d = std::hypot(p.x_m - t->x_m, p.y_m - t->y_m);
    const double h = wrapAngle(p.theta_rad - t->theta_rad);
    e.t_s.push_back(1e-6 * static_cast<double>(utime - t0));
    e.error_m.push_back(d);
    e.heading_error_rad.push_back(h);
    ss += d * d;
    mx = std::max(mx, d);
    hs += h * h;
    hm = std::max(hm, std::abs(h));
  }
  if (e.error_m.empty()) return e;
  e.rmse_m = std::sqrt(ss / static_cast<double>(e.error_m.size()));
  e.heading_rmse_rad = std::sqrt(hs / static_cast<double>(e.error_m.size()));
  e.heading_max_rad = hm;
  e.final_m = e.error_m.back();
  e.max_m = mx;
  return e;
}

// The track as points at height `z_m` (a top view's z band keeps them).
std::vector<Eigen::Vector3f> pathPoints(const PoseTrack& track, float z_m = 0.0f) {
  std::vector<Eigen::Vector3f> out;
  for (const auto& [utime, p] : track.poses()) {
    out.emplace_back(static_cast<float>(p.x_m), static_cast<float>(p.y_m), z_m);
  }
  return out;
}

Eigen::Vector3d centroid(const std::vector<Eigen::Vector3f>& cloud, const std::vector<int>& idx) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i : idx) c += cloud[static_cast<size_t>(i)].cast<double>();
  return idx.empty() ? c : Eigen::Vector3d(c / static_cast<double>(idx.size()));
}

double signedDistance(const WallPlaneFit& p, const Eigen::Vector3d& x) { return p.normal.dot(x) + p.offset; }

// Distance of two near-parallel planes: the mean of each one's distance from the other's
// inlier centroid (symmetric; exact for parallel planes).
double planeDistance(const WallPlaneFit& a, const std::vector<Eigen::Vector3f>& cloud_a,
                     const WallPlaneFit& b, const std::vector<Eigen::Vector3f>& cloud_b) {
  return 0.5 * (std::abs(signedDistance(a, centroid(cloud_b, b.inlier_indices))) +
                std::abs(signedDistance(b, centroid(cloud_a, a.inlier_indices))));
}

json planeJson(const WallPlaneFit& p, const std::vector<Eigen::Vector3f>& cloud) {
  const Eigen::Vector3d c = centroid(cloud, p.inlier_indices);
  return {{"normal", {round6(p.normal.x()), round6(p.normal.y()), round6(p.normal.z())}},
          {"offset_m", round6(p.offset)},
          {"centroid_m", {round6(c.x()), round6(c.y()), round6(c.z())}},
          {"inliers", p.inliers},
          {"rms_mm", round6(1000.0 * p.rms_m)}};
}

// The room's planes found by RANSAC in a world-frame cloud.
struct RoomPlanes {
  std::vector<WallPlaneFit> walls;  // extractWalls' order: normals ~ +Y, +X, -Y, -X
  std::optional<WallPlaneFit> floor, ceiling;
  std::string reason;  // what is missing
};

RoomPlanes findRoomPlanes(const std::vector<Eigen::Vector3f>& cloud) {
  RoomPlanes r;
  WallExtractionOptions wo;
  const WallExtraction walls = extractWalls(cloud, wo);
  r.walls = walls.walls;
  if (r.walls.empty()) r.reason = "walls: " + walls.reason;
  PlaneExtractionOptions ho;
  ho.orientation = PlaneExtractionOptions::Orientation::kHorizontal;
  ho.max_planes = 4;
  const auto horizontal = extractPlanes(cloud, ho);
  // Height of a horizontal plane: z where it crosses the vertical through its centroid.
  const auto height = [&](const WallPlaneFit& p) { return centroid(cloud, p.inlier_indices).z(); };
  for (const WallPlaneFit& p : horizontal) {
    if (!r.floor || height(p) < height(*r.floor)) r.floor = p;
    if (!r.ceiling || height(p) > height(*r.ceiling)) r.ceiling = p;
  }
  if (horizontal.size() < 2) {
    r.floor.reset();
    r.ceiling.reset();
    r.reason += (r.reason.empty() ? "" : "; ") + std::string("fewer than two horizontal planes");
  }
  return r;
}

struct RoomDims {
  std::optional<double> L1, L2, L3;  // length, width (the longer and shorter wall spacing), height
};

RoomDims roomDims(const RoomPlanes& p, const std::vector<Eigen::Vector3f>& cloud) {
  RoomDims d;
  if (p.walls.size() == 4) {
    const double y = planeDistance(p.walls[0], cloud, p.walls[2], cloud);
    const double x = planeDistance(p.walls[1], cloud, p.walls[3], cloud);
    d.L1 = std::max(x, y);
    d.L2 = std::min(x, y);
  }
  if (p.floor && p.ceiling) d.L3 = planeDistance(*p.floor, cloud, *p.ceiling, cloud);
  return d;
}

// Deviations (mm) of the points near each plane, for the histograms of Fig. 9.
DeviationStats deviations(const std::vector<Eigen::Vector3f>& cloud, const std::vector<WallPlaneFit>& planes,
                          double edge_trim_m) {
  std::vector<PlaneForDeviation> pd;
  for (const auto& p : planes) pd.push_back({p.normal, p.offset});
  DeviationStats stats(1.0, 50.0);
  for (const auto& v : wallDeviationsMm(cloud, pd, 0.05, edge_trim_m)) {
    for (double d : v) stats.add(d, 10.0);
  }
  return stats;
}

json deviationJson(const DeviationStats& d) {
  return {{"points", d.count},
          {"rms_mm", round6(d.rmsMm())},
          {"share_within_10mm", round6(d.shareWithin())},
          {"histogram", {{"bin_mm", d.bin_mm}, {"range_mm", d.range_mm}, {"counts", d.bins}}}};
}

// What the room's planes say of one world-frame cloud: the planes, L1-L3, the deviations
// of the ceiling and wall points (Fig. 9) and the ceiling's upward normal.
struct RoomMeasures {
  RoomPlanes planes;
  RoomDims dims;
  DeviationStats ceiling{1.0, 50.0}, walls{1.0, 50.0};
  std::optional<Eigen::Vector3d> ceiling_up;
};

RoomMeasures measureRoom(const std::vector<Eigen::Vector3f>& cloud) {
  RoomMeasures m;
  m.planes = findRoomPlanes(cloud);
  m.dims = roomDims(m.planes, cloud);
  const std::vector<WallPlaneFit> ceiling =
      m.planes.ceiling ? std::vector<WallPlaneFit>{*m.planes.ceiling} : std::vector<WallPlaneFit>{};
  m.ceiling = deviations(cloud, ceiling, 0.0);
  m.walls = deviations(cloud, m.planes.walls, 0.2);
  if (m.planes.ceiling) {
    m.ceiling_up = m.planes.ceiling->normal;
    if (m.ceiling_up->z() < 0) *m.ceiling_up = -*m.ceiling_up;
  }
  return m;
}

json dimsJson(const RoomDims& d) { return {{"L1", nullable(d.L1)}, {"L2", nullable(d.L2)}, {"L3", nullable(d.L3)}}; }

json vectorJson(const Eigen::Vector3d& v) { return {round6(v.x()), round6(v.y()), round6(v.z())}; }

// Where the drive comes back to a place it passed at least `min_gap_s` earlier (pose within
// `radius_m` and heading within `heading_rad`): the scans of both passes, and the distance
// between the planes each pass sees there. A double wall is the ghost of Miao 2022 Fig. 11.
struct LoopClosure {
  std::vector<int> early, late;  // scan indices
  struct Plane {
    WallPlaneFit early, late;
    double distance_m = 0;
  };
  std::vector<Plane> planes;
  std::vector<Eigen::Vector3f> early_points;  // the points the early planes index
  std::optional<double> ghost_m;  // the largest distance among vertical planes
  std::string reason;
};

LoopClosure loopClosure(const MobileLog& log, const PoseTrack& track, const std::vector<Eigen::Vector3f>& cloud,
                        const std::vector<int>& scan_of_point) {
  constexpr double kMinGapS = 30.0, kRadiusM = 0.3, kHeadingRad = 0.35;
  LoopClosure lc;
  std::vector<std::optional<Pose2>> pose(log.scans.size());
  for (size_t j = 0; j < log.scans.size(); ++j) {
    const Scan2D& s = log.scans[j];
    pose[j] = track.at(s.rayUtime(s.ranges_m.size() / 2));
  }
  std::vector<char> is_early(log.scans.size(), 0), is_late(log.scans.size(), 0);
  for (size_t j = 0; j < log.scans.size(); ++j) {
    if (!pose[j]) continue;
    for (size_t i = 0; i < j; ++i) {
      if (!pose[i] || 1e-6 * static_cast<double>(log.scans[j].utime - log.scans[i].utime) < kMinGapS) continue;
      if (std::hypot(pose[j]->x_m - pose[i]->x_m, pose[j]->y_m - pose[i]->y_m) > kRadiusM) continue;
      if (std::abs(wrapAngle(pose[j]->theta_rad - pose[i]->theta_rad)) > kHeadingRad) continue;
      is_early[i] = 1;
      is_late[j] = 1;
    }
  }
  std::vector<Eigen::Vector3f> early_pts, late_pts;
  for (size_t k = 0; k < cloud.size(); ++k) {
    const auto j = static_cast<size_t>(scan_of_point[k]);
    if (is_late[j]) {
      late_pts.push_back(cloud[k]);
    } else if (is_early[j]) {
      early_pts.push_back(cloud[k]);
    }
  }
  for (size_t j = 0; j < log.scans.size(); ++j) {
    if (is_early[j] && !is_late[j]) lc.early.push_back(static_cast<int>(j));
    if (is_late[j]) lc.late.push_back(static_cast<int>(j));
  }
  if (lc.early.size() < 5 || lc.late.size() < 5) {
    lc.reason = "the drive does not come back to a place it passed " + fixed(kMinGapS, 0) + " s earlier";
    return lc;
  }
  PlaneExtractionOptions po;
  po.orientation = PlaneExtractionOptions::Orientation::kVertical;
  po.voxel_m = 0.03;
  po.max_planes = 4;
  po.min_inliers = 100;
  po.distance_threshold_m = 0.03;
  for (const WallPlaneFit& e : extractPlanes(early_pts, po)) {
    // A far, noisy wall (1 % of 5 m) can come out of RANSAC as two parallel planes a few
    // centimetres apart, the second made of the first one's outliers: one surface, one plane.
    const Eigen::Vector3d c = centroid(early_pts, e.inlier_indices);
    const bool seen = std::any_of(lc.planes.begin(), lc.planes.end(), [&](const LoopClosure::Plane& q) {
      return std::abs(q.early.normal.dot(e.normal)) > std::cos(3.0 * M_PI / 180.0) &&
             std::abs(signedDistance(q.early, c)) < 0.1;
    });
    if (seen) continue;
    const auto refit = refitWalls(late_pts, {e}, 0.1);
    if (refit.empty() || refit[0].inliers < 100) continue;
    // The late pass's plane through its points near the early plane, then its own inliers.
    const auto late = refitWalls(late_pts, refit, po.distance_threshold_m);
    if (late.empty() || late[0].inliers < 100) continue;
    LoopClosure::Plane p{e, late[0], planeDistance(e, early_pts, late[0], late_pts)};
    lc.planes.push_back(p);
    lc.ghost_m = std::max(lc.ghost_m.value_or(0.0), p.distance_m);
  }
  if (!lc.ghost_m) lc.reason = "no wall seen by both passes";
  lc.early_points = std::move(early_pts);
  return lc;
}

std::vector<Eigen::Vector3f> sideView(const std::vector<Eigen::Vector3f>& cloud, int horizontal_axis) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(cloud.size());
  for (const auto& p : cloud) out.emplace_back(p[horizontal_axis], p.z(), 0.0f);
  return out;
}

Series histogramSeries(const DeviationStats& d, const std::string& title, const std::string& color,
                       const std::string& style) {
  Series s;
  s.title = title + ": RMS " + fixed(d.rmsMm(), 1) + " mm";
  s.color = color;
  s.style = style;
  for (size_t i = 0; i < d.bins.size(); ++i) {
    s.x.push_back(d.binCenterMm(i));
    s.y.push_back(static_cast<double>(d.bins[i]));
  }
  return s;
}

json mountingJson(const LidarMounting& m) {
  return {{"gamma_rad", round6(m.gamma_rad)}, {"beta_rad", round6(m.beta_rad)}, {"alpha_rad", round6(m.alpha_rad)}};
}

}  // namespace

EvalMobileResult evalMobileLog(const EvalMobileOptions& o) {
  EvalMobileResult result;
  const fs::path out(o.out_dir);
  fs::create_directories(out);
  const auto progress = [&](const std::string& what) {
    if (o.progress) std::cerr << "eval: " << what << "\n";
  };
  json& r = result.report;
  r["log"] = fs::path(o.log_path).filename().string();

  progress("replaying the odometry over " + o.log_path);
  MobileLog log;
  try {
    log = loadMobileLog(o.log_path, o.rig);
  } catch (const std::exception& e) {
    result.failed = true;
    result.message = e.what();
  }
  if (log.log_error) {
    result.failed = true;
    result.message = log.error;
    r["log_error"] = log.error;
  }
  r["scans"] = log.scans.size();
  r["invalid_scans"] = log.invalid_scans;
  if (log.scans.empty() || log.ekf.size() == 0) {
    result.failed = true;
    if (result.message.empty()) result.message = o.log_path + ": no valid scans or no odometry poses";
  }
  const PoseTrack& track = o.rig.assembler.pose_channel == "WHEEL_ODOMETRY" ? log.wheels : log.ekf;
  const LidarMounting mounting = o.rig.mounting.toMounting();
  r["mounting"] = mountingJson(mounting);
  r["pose_channel"] = o.rig.assembler.pose_channel;
  for (auto it = o.extra.begin(); it != o.extra.end(); ++it) r[it.key()] = it.value();
  Figures figures(out, o.plots);

  // Trajectory.
  const bool has_truth = log.truth.size() > 0;
  const TrajectoryErrors e_odo = trajectoryErrors(log.wheels, log.truth);
  const TrajectoryErrors e_ekf = trajectoryErrors(log.ekf, log.truth);
  r["trajectory_rmse_m"] = {{"odometry", nullable(e_odo.rmse_m)}, {"ekf", nullable(e_ekf.rmse_m)}};
  r["trajectory"] = {{"final_error_m", {{"odometry", nullable(e_odo.final_m)}, {"ekf", nullable(e_ekf.final_m)}}},
                     {"max_error_m", {{"odometry", nullable(e_odo.max_m)}, {"ekf", nullable(e_ekf.max_m)}}},
                     {"heading_rmse_mrad",
                      {{"odometry", nullable(e_odo.heading_rmse_rad ? std::optional<double>(1000.0 * *e_odo.heading_rmse_rad) : std::nullopt)},
                       {"ekf", nullable(e_ekf.heading_rmse_rad ? std::optional<double>(1000.0 * *e_ekf.heading_rmse_rad) : std::nullopt)}}},
                     {"wheel_readings_gated", log.gated_wheel_readings},
                     {"truth", has_truth}};
  if (e_odo.rmse_m && e_ekf.rmse_m && *e_ekf.rmse_m > 0) {
    r["trajectory"]["rmse_ratio_odometry_over_ekf"] = round6(*e_odo.rmse_m / *e_ekf.rmse_m);
  }
  {
    std::vector<Layer> layers;
    layers.push_back({"wheel odometry", "red", pathPoints(log.wheels)});
    layers.push_back({"EKF", "blue", pathPoints(log.ekf)});
    if (has_truth) layers.push_back({"truth", "black", pathPoints(log.truth)});
    PlotOptions po;
    po.title = has_truth ? "Trajectory: wheel odometry alone (red), EKF (blue, under the truth where it agrees), truth (black)"
                         : "Trajectory: wheel odometry alone (red), EKF (blue)";
    po.point_size = 0.15;
    figures.add("trajectory.png", "The car's path in the world frame (its start pose).",
                [&](const std::string& png) { plotTopView(png, layers, po); });
  }
  if (has_truth) {
    SeriesPlotOptions so;
    so.title = "Position error against the truth";
    so.x_label = "time [s]";
    so.y_label = "error [m]";
    const std::vector<Series> s = {{"wheel odometry", e_odo.t_s, e_odo.error_m, "lines", "red"},
                                   {"EKF", e_ekf.t_s, e_ekf.error_m, "lines", "blue"}};
    figures.add("trajectory_error.png",
                "Position error of wheel odometry alone and of the EKF; slip makes odometry drift.",
                [&](const std::string& png) { plotSeries(png, s, so); });
  }

  // The cloud.
  progress("assembling " + std::to_string(log.scans.size()) + " scans in the world frame");
  std::vector<int> scan_of_point;
  const auto cloud = assembleWorld(log, track, mounting, &scan_of_point);
  r["points"] = cloud.size();
  writePcdBinary((out / "cloud.pcd").string(), cloud);
  {
    PlotOptions po;
    po.point_size = 0.12;
    po.title = "Top view of the cloud (below 2 m) with the EKF path";
    po.z_band_m = PlotRange{0.05, 2.0};
    figures.add("top_view.png", "Top view (Fig. 11B): the cloud without floor and ceiling.",
                [&](const std::string& png) {
                  plotTopView(png, {{"cloud", "gray40", cloud}, {"EKF path", "blue", pathPoints(track, 1.0f)}}, po);
                });
    for (int axis : {0, 1}) {
      PlotOptions so;
      so.point_size = 0.12;
      so.x_label = axis == 0 ? "x [m]" : "y [m]";
      so.y_label = "z [m]";
      so.title = std::string("Side view of the cloud (") + (axis == 0 ? "x" : "y") + "-z)";
      const std::string file = std::string("side_view_") + (axis == 0 ? "xz" : "yz") + ".png";
      figures.add(file, "Side view: walls should stand vertical, floor and ceiling flat.",
                  [&](const std::string& png) { plotTopView(png, {{"cloud", "gray40", sideView(cloud, axis)}}, so); });
    }
  }

  // Planes, room dimensions, deviations.
  progress("RANSAC planes");
  const RoomMeasures room = measureRoom(cloud);
  const RoomPlanes& planes = room.planes;
  json jp;
  jp["walls"] = json::array();
  for (const auto& w : planes.walls) jp["walls"].push_back(planeJson(w, cloud));
  jp["floor"] = planes.floor ? planeJson(*planes.floor, cloud) : json(nullptr);
  jp["ceiling"] = planes.ceiling ? planeJson(*planes.ceiling, cloud) : json(nullptr);
  if (!planes.reason.empty()) jp["reason"] = planes.reason;
  r["planes"] = jp;
  if (room.ceiling_up) {
    r["ceiling_normal"] = vectorJson(*room.ceiling_up);
    r["ceiling_tilt_mrad"] = round6(1000.0 * std::acos(std::clamp(room.ceiling_up->z(), -1.0, 1.0)));
  } else {
    r["ceiling_normal"] = nullptr;
  }
  const RoomDims& dims = room.dims;
  r["room_dims_m"] = dimsJson(dims);
  if (log.truth_mounting) {
    const double* s = log.truth_mounting->room_size_m;
    const double t1 = std::max(s[0], s[1]), t2 = std::min(s[0], s[1]), t3 = s[2];
    r["room_dims_truth_m"] = {{"L1", t1}, {"L2", t2}, {"L3", t3}};
    const auto err = [](const std::optional<double>& v, double t) {
      return v ? json(round6(1000.0 * (*v - t))) : json(nullptr);
    };
    r["room_dims_error_mm"] = {{"L1", err(dims.L1, t1)}, {"L2", err(dims.L2, t2)}, {"L3", err(dims.L3, t3)}};
    const LidarMounting truth = trueMounting(*log.truth_mounting);
    r["mounting_truth"] = mountingJson(truth);
    r["mounting_used_error_mrad"] = {{"gamma", round6(1000.0 * (mounting.gamma_rad - truth.gamma_rad))},
                                     {"beta", round6(1000.0 * (mounting.beta_rad - truth.beta_rad))},
                                     {"alpha", round6(1000.0 * (mounting.alpha_rad - truth.alpha_rad))}};
  } else {
    r["room_dims_error_mm"] = {{"L1", nullptr}, {"L2", nullptr}, {"L3", nullptr}};
  }
  // The mounting's error against the truth: the experiment passes its calibration's; a log
  // evaluated on its own reports the mounting it was assembled with.
  if (!r.contains("mounting_error_mrad")) {
    r["mounting_error_mrad"] = r.contains("mounting_used_error_mrad") ? r["mounting_used_error_mrad"] : json(nullptr);
  }
  const DeviationStats& dev_ceiling = room.ceiling;
  const DeviationStats& dev_walls = room.walls;
  r["deviations"] = {{"ceiling", deviationJson(dev_ceiling)}, {"walls", deviationJson(dev_walls)}};
  if (o.before) {
    progress("the same with the mounting before calibration");
    const RoomMeasures rb = measureRoom(assembleWorld(log, track, *o.before));
    const DeviationStats& dc = rb.ceiling;
    const DeviationStats& dw = rb.walls;
    json b;
    b["mounting"] = mountingJson(*o.before);
    b["room_dims_m"] = dimsJson(rb.dims);
    b["deviations"] = {{"ceiling", deviationJson(dc)}, {"walls", deviationJson(dw)}};
    if (rb.ceiling_up) b["ceiling_normal"] = vectorJson(*rb.ceiling_up);
    r["before_calibration"] = b;
    for (const auto& [name, before, after] :
         {std::tuple<std::string, const DeviationStats*, const DeviationStats*>{"ceiling", &dc, &dev_ceiling},
          {"walls", &dw, &dev_walls}}) {
      SeriesPlotOptions so;
      so.title = "Fig. 9: deviations of the " + name + " points from their RANSAC plane";
      so.x_label = "deviation [mm]";
      so.y_label = "points";
      const std::vector<Series> s = {histogramSeries(*before, "uncalibrated", "#cc3311", "boxes"),
                                     histogramSeries(*after, "calibrated", "#1f4fd8", "lines")};
      figures.add("deviation_" + name + ".png",
                  "Fig. 9: histogram of the " + name +
                      " deviations before (red) and after (blue) the mounting calibration; the "
                      "calibrated one should be narrower.",
                  [&, s, so](const std::string& png) { plotSeries(png, s, so); });
    }
  } else {
    SeriesPlotOptions so;
    so.title = "Deviations of the ceiling and wall points from their RANSAC planes";
    so.x_label = "deviation [mm]";
    so.y_label = "points";
    const std::vector<Series> s = {histogramSeries(dev_ceiling, "ceiling", "#1f4fd8", "lines"),
                                   histogramSeries(dev_walls, "walls", "#228833", "lines")};
    figures.add("deviations.png", "Fig. 9: histograms of the plane deviations.",
                [&](const std::string& png) { plotSeries(png, s, so); });
  }

  // Density (Eq. 18-19).
  progress("density D over " + std::to_string(cloud.size()) + " points");
  r["density_D_m"] = round6(meanNearestNeighbourDistance(cloud));

  // The ghost where the drive closes its loop.
  progress("loop closure");
  const LoopClosure lc = loopClosure(log, track, cloud, scan_of_point);
  r["ghost_mm"] = lc.ghost_m ? json(round6(1000.0 * *lc.ghost_m)) : json(nullptr);
  json jl;
  jl["early_scans"] = lc.early.size();
  jl["late_scans"] = lc.late.size();
  jl["planes"] = json::array();
  for (const auto& p : lc.planes) {
    jl["planes"].push_back({{"normal", {round6(p.early.normal.x()), round6(p.early.normal.y()), round6(p.early.normal.z())}},
                            {"centroid_m", planeJson(p.early, lc.early_points)["centroid_m"]},
                            {"early_points", p.early.inliers},
                            {"late_points", p.late.inliers},
                            {"distance_mm", round6(1000.0 * p.distance_m)}});
  }
  if (!lc.reason.empty()) jl["reason"] = lc.reason;
  r["loop_closure"] = jl;
  if (!lc.late.empty()) {
    std::vector<char> early(log.scans.size(), 0), late(log.scans.size(), 0);
    for (int j : lc.early) early[static_cast<size_t>(j)] = 1;
    for (int j : lc.late) late[static_cast<size_t>(j)] = 1;
    std::vector<Eigen::Vector3f> pe, pl;
    for (size_t k = 0; k < cloud.size(); ++k) {
      const auto j = static_cast<size_t>(scan_of_point[k]);
      if (late[j]) pl.push_back(cloud[k]);
      if (early[j]) pe.push_back(cloud[k]);
    }
    PlotOptions po;
    po.point_size = 0.2;
    po.z_band_m = PlotRange{0.9, 1.1};
    po.title = "Where the loop closes: first pass (blue) and last pass (red), z 0.9-1.1 m; ghost " +
               (lc.ghost_m ? fixed(1000.0 * *lc.ghost_m, 1) + " mm" : std::string("n/a"));
    figures.add("loop_closure.png",
                "Fig. 11C-D: the walls seen where the drive comes back to its start, first pass "
                "against last pass; a double wall is the ghost.",
                [&](const std::string& png) { plotTopView(png, {{"first pass", "blue", pe}, {"last pass", "red", pl}}, po); });
  }

  // Figures list and the report files.
  std::vector<Figures::Entry> all_figures;
  for (const auto& [file, caption] : o.extra_figures) all_figures.push_back({file, caption});
  all_figures.insert(all_figures.end(), figures.files().begin(), figures.files().end());
  r["figures"] = json::array();
  for (const auto& f : all_figures) r["figures"].push_back(f.file);
  if (!figures.errors().empty()) r["figure_errors"] = figures.errors();
  writeFileAtomic((out / "report.json").string(), r.dump(2) + "\n");

  std::ostringstream md;
  md << "# Rig B evaluation: " << r["log"].get<std::string>() << "\n\n";
  md << "- scans " << log.scans.size() << ", points " << cloud.size() << ", poses from "
     << o.rig.assembler.pose_channel << "\n";
  md << "- trajectory RMSE: odometry " << r["trajectory_rmse_m"]["odometry"].dump() << " m, EKF "
     << r["trajectory_rmse_m"]["ekf"].dump() << " m\n";
  md << "- room dimensions L1, L2, L3: " << r["room_dims_m"].dump() << " m; error "
     << r["room_dims_error_mm"].dump() << " mm\n";
  md << "- ceiling normal " << r["ceiling_normal"].dump() << "; density D " << r["density_D_m"].dump()
     << " m; ghost where the loop closes " << r["ghost_mm"].dump() << " mm\n";
  md << "- mounting (gamma, beta, alpha) " << r["mounting"].dump() << "; error against the truth "
     << r["mounting_error_mrad"].dump() << " mrad\n";
  if (r.contains("calibration")) {
    const json& c = r["calibration"];
    md << "- calibration from the circle: ours " << c["ours"].value("error_mrad", json(nullptr)).dump()
       << " mrad (residual " << c["ours"]["residual_before_m"].dump() << " -> " << c["ours"]["residual_after_m"].dump()
       << " m), the paper's " << c["paper"].value("error_mrad", json(nullptr)).dump() << " mrad; circle double wall "
       << c["circle_double_wall_mm"]["before"]["max_mm"].dump() << " mm before, "
       << c["circle_double_wall_mm"]["after"]["max_mm"].dump() << " mm after\n";
  }
  md << "\n";
  for (const auto& f : all_figures) md << "![" << f.caption << "](" << f.file << ")\n\n" << f.caption << "\n\n";
  writeFileAtomic((out / "report.md").string(), md.str());
  return result;
}

}  // namespace sweepmap

namespace sweepmap {
namespace {

// The scan's rays on one side of the lidar's Z_L-axis only (left: angles in (0, pi), toward
// +Y_L, the body's left with the nominal vertical mounting); the others become "no return".
// So do returns beyond 90 % of the maximum range: near it only the readings whose noise made
// them short survive, so a wall there is biased toward the sensor, more for the pass that sees
// it from farther (18 mm on the lab's far wall, 9-11 m from the circle).
Scan2D scanHalf(const Scan2D& scan, bool left) {
  Scan2D half = scan;
  const float far = float(0.9 * scan.range_max_m);
  for (size_t i = 0; i < half.ranges_m.size(); ++i) {
    const bool is_left = std::sin(half.rayAngle(i)) > 0.0;
    if (is_left != left || half.ranges_m[i] > far) half.ranges_m[i] = 0.0f;
  }
  return half;
}

// The double walls of a drive that sees each place with both halves of its scan (the
// calibration circle): every wall fitted in the left halves' cloud and in the right halves',
// and the distance between the two copies along the wall's normal. With the right mounting
// the two coincide.
struct HalfScanGhost {
  std::vector<Eigen::Vector3f> left, right;
  std::vector<double> wall_distance_m;  // per wall found in both halves
  std::optional<double> max_m;
  std::string reason;
};

HalfScanGhost halfScanGhost(const MobileLog& log, const PoseTrack& track, const LidarMounting& mounting) {
  HalfScanGhost g;
  const Eigen::Isometry3d T_BL = mounting.T_BL();
  for (const Scan2D& s : log.scans) {
    for (bool left : {true, false}) {
      const auto pts = scanToWorld(scanHalf(s, left), track, T_BL);
      auto& dst = left ? g.left : g.right;
      dst.insert(dst.end(), pts.begin(), pts.end());
    }
  }
  // The walls of both halves together, then each wall refitted in each half on its own: a
  // band wide enough to hold both copies of a doubled wall, then the half's own inliers.
  std::vector<Eigen::Vector3f> both = g.left;
  both.insert(both.end(), g.right.begin(), g.right.end());
  // Vertical planes (the circle sees the far walls only at grazing, noisy ranges: any large
  // vertical plane will do, not necessarily four facing walls). A band of 6 cm catches both
  // copies of a wall doubled by a few centimetres.
  PlaneExtractionOptions po;
  po.orientation = PlaneExtractionOptions::Orientation::kVertical;
  po.distance_threshold_m = 0.06;
  po.max_planes = 4;
  const std::vector<WallPlaneFit> walls = extractPlanes(both, po);
  if (walls.empty()) {
    g.reason = "no vertical plane found";
    return g;
  }
  const auto refit = [](const std::vector<Eigen::Vector3f>& half, const WallPlaneFit& w) {
    const auto wide = refitWalls(half, {w}, 0.15);
    if (wide.empty() || wide[0].inliers < 100) return std::optional<WallPlaneFit>();
    const auto tight = refitWalls(half, wide, 0.03);
    if (tight.empty() || tight[0].inliers < 100) return std::optional<WallPlaneFit>();
    return std::optional<WallPlaneFit>(tight[0]);
  };
  for (const WallPlaneFit& w : walls) {
    const auto l = refit(g.left, w), r = refit(g.right, w);
    if (!l || !r) continue;
    // The two copies' offsets along the common normal (both halves' fit): each half's
    // inliers averaged, so a far, sparse wall's noisy tilt does not reach the other copy
    // over a lever of metres (as the distance of one half's plane from the other's
    // centroid did: 16 mm on the lab's far wall, 10 m from the circle, after calibration).
    const auto meanOffset = [&](const std::vector<Eigen::Vector3f>& half, const WallPlaneFit& fit) {
      double sum = 0.0;
      for (int i : fit.inlier_indices) sum += signedDistance(w, half[size_t(i)].cast<double>());
      return sum / double(fit.inlier_indices.size());
    };
    const double d = std::abs(meanOffset(g.left, *l) - meanOffset(g.right, *r));
    g.wall_distance_m.push_back(d);
    g.max_m = std::max(g.max_m.value_or(0.0), d);
  }
  if (!g.max_m) g.reason = "no wall seen by both halves";
  return g;
}

}  // namespace

EvalMobileResult runMobilePaperExperiment(const MobileExperimentOptions& o) {
  const fs::path out(o.out_dir);
  fs::create_directories(out / "logs");
  const auto progress = [&](const std::string& what) {
    if (o.progress) std::cerr << "eval: " << what << "\n";
  };
  // The paper's two runs: the calibration circle (r = 0.83 m) and one lap of the lab loop
  // at 0.2 m/s, from the same rig and scene files.
  const auto simulateTo = [&](const std::string& name, const std::string& path, double duration_s,
                              uint64_t seed, MobileLidarConfig* rig, SceneConfig* scene) {
    std::vector<std::string> overrides = o.overrides;
    overrides.push_back("sim.path=" + path);
    overrides.push_back("sim.duration_s=" + fixed(duration_s, 3));
    SimMobileOptions so;
    const SimSetup setup = loadSimSetup(o.rig_path, o.scene_path, overrides);
    so.rig = requireKind<MobileLidarConfig>(setup.rig, "this experiment");
    so.scene = setup.scene;
    so.seed = seed;
    const std::string log_path = (out / "logs" / (name + ".lcmlog")).string();
    progress("simulating the " + name + " (" + fixed(duration_s, 0) + " s) -> " + log_path);
    EventLogWriter w(log_path);
    simulateMobile(so, [&](const Message& m) { w.write(m.utime, m.channel, m.data); });
    w.close();
    *rig = so.rig;
    *scene = so.scene;
    return log_path;
  };
  MobileLidarConfig circle_rig, loop_rig;
  SceneConfig scene;
  const std::string circle_log = simulateTo("circle", "circle", o.circle_duration_s, o.seed, &circle_rig, &scene);
  const std::string loop_log = simulateTo("loop", "loop", o.loop_duration_s, o.seed + 1, &loop_rig, &scene);

  // Calibration from the circle, both methods, starting from the rig file's mounting.
  progress("calibrating the mounting from the circle (ours: point-to-plane; the paper's: target points)");
  const MobileLog circle = loadMobileLog(circle_log, circle_rig);
  const LidarMounting initial = circle_rig.mounting.toMounting();
  std::optional<LidarMounting> truth;
  if (circle.truth_mounting) truth = trueMounting(*circle.truth_mounting);
  MountingCalibrationOptions ours_options;
  ours_options.method = MountingMethod::kPointToPlane;
  MountingCalibrationOptions paper_options;
  paper_options.method = MountingMethod::kPaperPoints;
  const MountingCalibrationResult ours = calibrateMounting(circle.scans, circle.ekf, initial, ours_options);
  const MountingCalibrationResult paper = calibrateMounting(circle.scans, circle.ekf, initial, paper_options);
  json calibration = {{"log", "logs/circle.lcmlog"},
                      {"ours", json::parse(mountingResultJsonText(ours, truth))},
                      {"paper", json::parse(mountingResultJsonText(paper, truth))}};
  if (truth) calibration["truth"] = mountingJson(*truth);

  EvalMobileOptions eo;
  eo.log_path = loop_log;
  eo.rig = loop_rig;
  eo.out_dir = o.out_dir;
  eo.plots = o.plots;
  eo.progress = o.progress;
  eo.before = initial;
  if (!ours.ok) {
    EvalMobileResult r;
    r.failed = true;
    r.message = "mounting calibration failed: " + ours.reason;
    r.report = {{"experiment", "paper"}, {"calibration", calibration}};
    writeFileAtomic((out / "report.json").string(), r.report.dump(2) + "\n");
    return r;
  }
  LidarMounting calibrated = initial;
  calibrated.gamma_rad = ours.gamma_rad;
  calibrated.beta_rad = ours.beta_rad;
  calibrated.alpha_rad = ours.alpha_rad;
  eo.rig.mounting.gamma_rad = ours.gamma_rad;
  eo.rig.mounting.beta_rad = ours.beta_rad;
  eo.rig.mounting.alpha_rad = ours.alpha_rad;
  {
    MountingCalibration file;
    file.gamma_rad = ours.gamma_rad;
    file.beta_rad = ours.beta_rad;
    file.alpha_rad = ours.alpha_rad;
    file.source["tool"] = "sweepmap eval --experiment paper (mobile_lidar)";
    file.source["method"] = mountingMethodName(ours.method);
    file.logs = {"logs/circle.lcmlog"};
    writeMountingCalibration((out / "mounting_calibration.yaml").string(), file);
  }

  // The circle's double walls before and after (Fig. 6-7), and a close-up of the target
  // (its box in the world frame: the scene's room frame moved by TRUTH_MOUNTING's start pose).
  progress("double walls of the circle before and after calibration");
  std::optional<Eigen::AlignedBox3d> target_world;
  if (const auto board = Scene(scene, PlateConfig{}).targetBoard(); board && circle.truth_mounting) {
    const double* w = circle.truth_mounting->world_in_room;
    const Eigen::Isometry3d T_world_room = planarToIsometry(Pose2{w[0], w[1], w[2]}).inverse();
    target_world = Eigen::AlignedBox3d(T_world_room * board->min());
    target_world->extend(T_world_room * board->max());
  }
  Figures figures(out, o.plots);
  json ghost;
  for (const auto& [name, mounting] :
       {std::pair<std::string, LidarMounting>{"before", initial}, {"after", calibrated}}) {
    const HalfScanGhost g = halfScanGhost(circle, circle.ekf, mounting);
    json jg = {{"max_mm", g.max_m ? json(round6(1000.0 * *g.max_m)) : json(nullptr)},
               {"walls_mm", json::array()}};
    for (double d : g.wall_distance_m) jg["walls_mm"].push_back(round6(1000.0 * d));
    if (!g.reason.empty()) jg["reason"] = g.reason;
    ghost[name] = jg;
    PlotOptions po;
    po.point_size = 0.2;
    po.z_band_m = PlotRange{0.9, 1.1};
    po.title = "Calibration circle, " + name + " calibration: left (blue) and right (red) halves of the scans, z 0.9-1.1 m; double wall " +
               (g.max_m ? fixed(1000.0 * *g.max_m, 1) + " mm" : std::string("n/a"));
    figures.add("circle_ghost_" + name + ".png",
                "Fig. 6-7: the calibration circle sees every wall with both halves of the scan; " + name +
                    " calibration" + (name == "before" ? ", the mounting error splits each wall in two (the ghost)."
                                                       : ", the two halves coincide."),
                [&](const std::string& png) {
                  plotTopView(png, {{"left halves", "blue", g.left}, {"right halves", "red", g.right}}, po);
                });
    if (target_world) {  // the same, close up on the calibration target
      PlotOptions zo = po;
      const Eigen::Vector3d c = target_world->center();
      zo.x_range_m = PlotRange{c.x() - 0.8, c.x() + 0.8};
      zo.y_range_m = PlotRange{c.y() - 0.8, c.y() + 0.8};
      zo.z_band_m = PlotRange{target_world->min().z(), target_world->max().z()};
      zo.point_size = 0.4;
      zo.title = "Calibration target (board before a window), " + name + " calibration: left halves (blue), right halves (red)";
      figures.add("target_ghost_" + name + ".png",
                  "Fig. 6-7, close up: the board in front of the window recess at the board's height, " + name +
                      " calibration" + (name == "before" ? ": two boards." : ": one board."),
                  [&](const std::string& png) {
                    plotTopView(png, {{"left halves", "blue", g.left}, {"right halves", "red", g.right}}, zo);
                  });
    }
  }
  calibration["circle_double_wall_mm"] = ghost;
  for (const auto& f : figures.files()) eo.extra_figures.emplace_back(f.file, f.caption);

  eo.extra = {{"experiment", "paper"},
              {"calibration", calibration},
              {"mounting_error_mrad", truth ? calibration["ours"]["error_mrad"] : json(nullptr)},
              {"mounting_error_mrad_paper", truth ? calibration["paper"]["error_mrad"] : json(nullptr)}};
  progress("evaluating the loop with our calibration");
  return evalMobileLog(eo);
}

}  // namespace sweepmap
