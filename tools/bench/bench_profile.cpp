#include "tools/bench/bench_profile.hpp"

#include <algorithm>
#include <ios>
#include <vector>

#include "calib/axis_offset.hpp"
#include "rigs/rig_file.hpp"
#include "tools/offline/calibrate_axis_offset.hpp"

namespace sweepmap {
namespace {

// The rig's plate poses, one PlanePoints each, as the log reader makes them.
std::vector<PlanePoints> simulatedPlates(const RotatingProfileConfig& rig, uint64_t seed) {
  SimProfiler profiler(rig.profiler, rig.turntable, rig.sim, seed);
  std::vector<PlanePoints> planes;
  int32_t id = 0;
  for (const PlatePose& pose : platePoses(rig.sim, rig.turntable)) {
    PlanePoints plane{"sweep " + std::to_string(id), {}};
    for (const Profile& p : profiler.sweep(ProfileScene::plate(pose), id, 0)) {
      const double a = turntableAngleRad(p.encoder_counts, p.counts_per_revolution, 0.0);
      for (size_t i = 0; i < p.y_mm.size(); ++i) plane.samples.push_back({p.y_mm[i], p.z_mm[i], a});
    }
    planes.push_back(std::move(plane));
    ++id;
  }
  return planes;
}

}  // namespace

int benchProfile(const ProfileBenchOptions& o, std::ostream& out) {
  const std::ios::fmtflags flags = out.flags();
  const std::streamsize precision = out.precision(4);
  out.unsetf(std::ios::floatfield);
  const Rig loaded = loadRig(o.rig, {"sim.scene=plate"});
  const RotatingProfileConfig& rig = requireKind<RotatingProfileConfig>(loaded, "the rig-C bench");
  const int max_points = AxisOffsetCalibRequest{}.max_points_per_sweep;
  std::vector<PlanePoints> planes;
  size_t full = 0, used = 0;
  for (const PlanePoints& p : simulatedPlates(rig, o.seed)) {
    full += p.samples.size();
    planes.push_back(subsample(p, max_points));
    used += planes.back().samples.size();
  }
  out << "axis-offset calibration, " << planes.size() << " plate poses, " << used << " of " << full
      << " points (calib axis-offset's default " << max_points << " per pose)\n";
  AxisOffsetOptions ao;
  ao.initial = rig.geometry.toGeometry();
  std::vector<double> ours_s;
  AxisOffsetResult ours;
  for (int k = 0; k < std::max(1, o.repeats); ++k) {
    ours = solveAxisOffset(planes, ao);
    ours_s.push_back(ours.seconds);
  }
  std::sort(ours_s.begin(), ours_s.end());
  const double ours_median = ours_s[ours_s.size() / 2];
  const ProfileGeometry truth = rig.sim.trueGeometry();
  out << "  ours (Ceres: M, N, tilt, planes; covariance, observability) " << ours_median
      << " s (median of " << ours_s.size() << "), " << ours.iterations << " iterations, M "
      << ours.geometry.m_mm - truth.m_mm << " mm, N " << ours.geometry.n_mm - truth.n_mm
      << " mm from the truth\n";
  for (const double step : {1.0, 0.1}) {
    GridSearchOptions g;
    g.step_mm = step;
    const GridSearchResult r = gridSearchAxisOffset(planes, g);
    out << "  paper's grid " << step << " mm over M " << g.m_min_mm << "-" << g.m_max_mm << ", N "
        << g.n_min_mm << "-" << g.n_max_mm << ": " << r.s_mm.size() << " evaluations, " << r.seconds
        << " s, M " << r.m_mm - truth.m_mm << " mm, N " << r.n_mm - truth.n_mm
        << " mm from the truth; grid / ours = " << r.seconds / ours_median << "x\n";
  }
  out.flags(flags);
  out.precision(precision);
  return 0;
}

}  // namespace sweepmap
