#include "tools/eval/rotating_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "calib/rotating_geometry.hpp"
#include "calib/walls.hpp"
#include "tools/eval/common.hpp"
#include "tools/offline/log_sweeps.hpp"

namespace sweepmap::eval {

const char* methodKey(Method m) {
  switch (m) {
    case Method::kRayPlane:
      return "ray_plane";
    case Method::kCentroid:
      return "centroid";
    case Method::kUncorrected:
      return "uncorrected";
  }
  return "";
}

MethodRigs methodRigs(const RotatingLidarConfig& rig) {
  MethodRigs r{rig, rig};
  r.ray_plane.plate.beta_method = "ray_plane";
  r.centroid.plate.beta_method = "centroid";
  return r;
}

namespace {

// What the centroid pass keeps of a sweep, by sweep id.
struct CentroidResult {
  bool corrected;
  std::string reason;
  double phi_offset_rad;
  double alpha_rad;
};

std::map<int64_t, CentroidResult> centroidPass(const std::string& path,
                                               const RotatingLidarConfig& rig) {
  std::map<int64_t, CentroidResult> centroid;
  forEachSweep(path, rig, [&](const AssembledSweep& sw, const SweepTruth&) {
    centroid[sw.window.sweep_id] = {sw.corrected, sw.reason, sw.phi_offset_rad, sw.alpha_rad};
  });
  return centroid;
}

// The record of a sweep assembled by ray_plane, with the centroid pass's result for it.
SweepRecord sweepRecord(const std::string& log_name, const AssembledSweep& sw,
                        const SweepTruth& truth,
                        const std::map<int64_t, CentroidResult>& centroid) {
  SweepRecord r;
  r.log = log_name;
  r.id = sw.window.sweep_id;
  r.mode = sw.window.mode;
  r.points = sw.points.size();
  r.plate_points = sw.plate.points;
  r.corrected = sw.corrected;
  r.reason = sw.reason;
  r.phi_offset_rad = sw.phi_offset_rad;
  r.alpha_used_rad = sw.alpha_rad;
  const auto c = centroid.find(r.id);
  if (c != centroid.end()) {
    r.has_centroid = true;
    r.corrected_centroid = c->second.corrected;
    r.reason_centroid = c->second.reason;
    r.phi_offset_centroid_rad = c->second.phi_offset_rad;
    r.alpha_used_centroid_rad = c->second.alpha_rad;
  }
  r.phi_true_rad = truth.phi_true_rad;
  return r;
}

// The walls of the published cloud: their normals and the deviations of their points.
void measureWalls(const std::vector<Eigen::Vector3f>& cloud, const EvalSettings& s,
                  SweepRecord* r) {
  WallExtractionOptions wo;
  wo.voxel_m = s.wall_voxel_m;
  const WallExtraction ex = extractWalls(cloud, wo);
  r->deviations = DeviationStats(s.histogram_bin_mm, 1000.0 * s.band_m);
  if (ex.walls.empty()) {
    r->walls_reason = ex.reason.empty() ? "no walls found" : ex.reason;
    return;
  }
  const std::vector<WallPlaneFit> fits = refitWalls(cloud, ex.walls, kRefitDistanceM);
  std::vector<PlaneForDeviation> planes;
  for (const auto& f : fits) {
    if (f.inliers < 3) continue;
    planes.push_back({f.normal, f.offset});
    r->wall_normals.push_back(f.normal);
  }
  for (const auto& wall : wallDeviationsMm(cloud, planes, s.band_m, s.edge_trim_m)) {
    for (double d : wall) r->deviations.add(d, s.within_mm);
  }
}

void appendTopView(const std::vector<Eigen::Vector3f>& cloud, const EvalSettings& s,
                   std::vector<Eigen::Vector3f>* out) {
  size_t in_band = 0;
  for (const auto& p : cloud) {
    if (p.z() >= s.top_view_z_min_m && p.z() <= s.top_view_z_max_m) ++in_band;
  }
  const size_t stride = std::max<size_t>(1, (in_band + s.top_view_points_per_sweep - 1) /
                                                std::max<size_t>(1, s.top_view_points_per_sweep));
  size_t k = 0;
  for (const auto& p : cloud) {
    if (p.z() < s.top_view_z_min_m || p.z() > s.top_view_z_max_m) continue;
    if (k++ % stride == 0) out->push_back(p);
  }
}

// Adds the sweep's deviations and (with `top_views`) its top views to the group; called
// before the sweep's record joins the group.
void addToGroup(const AssembledSweep& sw, const SweepRecord& r, const EvalSettings& s,
                bool top_views, Group* g) {
  if (g->deviations.bins.empty())
    g->deviations = DeviationStats(s.histogram_bin_mm, 1000.0 * s.band_m);
  g->deviations.merge(r.deviations);
  if (top_views) {
    appendTopView(sw.points_Op, s, &g->top_Op);
    appendTopView(sw.points, s, &g->top_O);
    if (g->sweeps.empty()) {
      g->first_sweep_top_points = g->top_Op.size();
      g->first_sweep_O = sw.points;
    }
  }
}

std::string sweepProgressLine(const std::string& log_name, const SweepRecord& r,
                              const Stopwatch& watch) {
  std::ostringstream line;
  line << log_name << ": sweep " << r.id << " (mode " << r.mode << ", " << r.points << " points)";
  if (const auto e = r.phiErrorRad(Method::kRayPlane)) {
    line << " phi_error " << fixed(*e * kRadToDeg, 3) << " deg";
  }
  if (!r.corrected) line << " not corrected: " << r.reason;
  line << ", " << r.wall_normals.size() << " walls, RMS " << fixed(r.deviations.rmsMm(), 1)
       << " mm  [" << fixed(watch.seconds(), 1) << " s]";
  return line.str();
}

}  // namespace

LogStatus evaluateLog(const std::string& path, const std::string& role, const MethodRigs& rigs,
                      const EvalSettings& s, bool top_views,
                      const std::function<Group&(int mode)>& group_for) {
  Stopwatch watch;
  LogStatus status;
  status.path = path;
  status.role = role;
  const std::string name = std::filesystem::path(path).filename().string();

  progressLine(s.progress, name + ": pass 1/2 (beta by centroid)");
  const std::map<int64_t, CentroidResult> centroid = centroidPass(path, rigs.centroid);
  progressLine(s.progress, name + ": pass 2/2 (beta by ray_plane), walls  [" +
                               fixed(watch.seconds(), 1) + " s]");

  const LogReadResult read =
      forEachSweep(path, rigs.ray_plane, [&](const AssembledSweep& sw, const SweepTruth& truth) {
        SweepRecord r = sweepRecord(name, sw, truth, centroid);
        measureWalls(sw.points, s, &r);
        Group& g = group_for(r.mode);
        addToGroup(sw, r, s, top_views, &g);
        progressLine(s.progress, sweepProgressLine(name, r, watch));
        g.sweeps.push_back(std::move(r));
        ++status.sweeps;
      });
  status.events = read.events;
  status.error = read.log_error;
  status.message = read.error;
  status.alpha_true_rad = read.alpha_true_rad;
  status.scene = read.scene;
  status.skipped_channels = read.skipped_channels;
  status.seconds = watch.seconds();
  if (status.error) progressLine(s.progress, name + ": " + status.message);
  return status;
}

PhiStats phiStats(const std::vector<SweepRecord>& sweeps, Method m) {
  PhiStats st;
  double sum = 0;
  for (const auto& r : sweeps) {
    const auto e = r.phiErrorRad(m);
    if (!e) continue;
    if (!r.correctedBy(m)) {
      ++st.uncorrected;
      continue;
    }
    const double d = *e * kRadToDeg;
    if (st.sweeps == 0) st.max = st.min = d;
    st.max = std::max(st.max, d);
    st.min = std::min(st.min, d);
    st.max_abs = std::max(st.max_abs, std::abs(d));
    sum += d;
    ++st.sweeps;
  }
  if (st.sweeps > 0) st.mean = sum / st.sweeps;
  return st;
}

// The centroid method's clouds are the default method's rotated by (phi_c - phi_r), and so
// are their normals.
AlphaCalibration calibrateAlpha(const std::vector<const SweepRecord*>& records, Method method,
                                double alpha0_rad) {
  AlphaCalibration a;
  a.alpha0_rad = alpha0_rad;
  std::vector<SweepNormals> sweeps;
  for (const SweepRecord* r : records) {
    if (r->wall_normals.empty() || !r->corrected) continue;
    SweepNormals sn;
    if (method == Method::kCentroid) {
      if (!r->has_centroid || !r->corrected_centroid) continue;
      const Eigen::Matrix3d R = rotating::rotZ(r->phi_offset_centroid_rad - r->phi_offset_rad);
      for (const auto& n : r->wall_normals) sn.normals.push_back(R * n);
      sn.alpha_used_rad = r->alpha_used_centroid_rad;
    } else {
      sn.normals = r->wall_normals;
      sn.alpha_used_rad = r->alpha_used_rad;
    }
    sweeps.push_back(std::move(sn));
  }
  a.sweeps_used = static_cast<int>(sweeps.size());
  if (sweeps.empty()) {
    a.reason = records.empty() ? "no mode-7 sweep" : "no corrected mode-7 sweep with four walls";
    return a;
  }
  LmOptions lo;
  lo.alpha0_rad = alpha0_rad;
  a.lm = calibratePlateAngle(sweeps, lo);
  for (const auto& sn : sweeps) {
    a.e_atti_before += attitudeError(sn) / static_cast<double>(sweeps.size());
    a.e_atti_after += fCost(sn, a.lm.alpha_rad) / static_cast<double>(sweeps.size());
  }
  a.done = true;
  return a;
}

}  // namespace sweepmap::eval
