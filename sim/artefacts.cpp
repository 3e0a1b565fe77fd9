#include "sim/artefacts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/angles.hpp"
#include "sim/reflectance.hpp"

namespace sweepmap {
namespace {

constexpr double kEdgeJumpM = 0.05;
constexpr double kWalkSpeedMS = 1.0;

// Entry distance of the ray into `box` within (0, limit), if any, and the axis of the face
// it enters through.
std::optional<double> rayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                             const Eigen::AlignedBox3d& box, double limit, int* axis) {
  double t0 = 0.0, t1 = limit;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (o[k] < box.min()[k] || o[k] > box.max()[k]) return std::nullopt;
      continue;
    }
    double a = (box.min()[k] - o[k]) / d[k], b = (box.max()[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    if (a > t0) *axis = k;
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return std::nullopt;
  }
  if (!(t0 > 0.0)) return std::nullopt;
  return t0;
}

}  // namespace

bool glancingDropout(double incidence_deg, double at_90_deg, std::mt19937_64& rng) {
  if (!(incidence_deg > 70.0) || !(at_90_deg > 0)) return false;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  return uniform(rng) < at_90_deg * (incidence_deg - 70.0) / 20.0;
}

SceneArtefacts::SceneArtefacts(const SceneArtefactConfig& sim, const Scene& scene, uint64_t seed)
    : sim_(sim), scene_(&scene) {
  reseed(seed);
  const SceneConfig& c = scene.config();
  const double l = c.room_length_m / 2, w = c.room_width_m / 2;
  if (sim.whiteboard_proud_mm > 0) {
    const double proud = sim.whiteboard_proud_mm * 1e-3, top = std::min(2.1, c.room_height_m);
    const bool target_there = c.target_enabled && c.target_wall == "x_min";
    whiteboard_ = target_there ? Eigen::AlignedBox3d(Eigen::Vector3d(l - proud, 0.5 - 1.0, 0.9),
                                                     Eigen::Vector3d(l, 0.5 + 1.0, top))
                               : Eigen::AlignedBox3d(Eigen::Vector3d(-l, 0.5 - 1.0, 0.9),
                                                     Eigen::Vector3d(-l + proud, 0.5 + 1.0, top));
  }
  if (sim.window_width_m > 0) {
    window_xz_ = Eigen::AlignedBox2d(Eigen::Vector2d(-1.0 - sim.window_width_m / 2, 0.9),
                                     Eigen::Vector2d(-1.0 + sim.window_width_m / 2, 2.1));
  }
  for (const SceneBox& b : scene.boxes()) {
    dark_.push_back(b.name.rfind("table", 0) == 0 || b.name == "cabinet");
  }
  walk_x0_ = -l + 0.5;
  walk_x1_ = l - 0.5;
  const double lanes[] = {-1.6, 2.2, -1.0, 1.6};
  for (int i = 0; i < sim.people; ++i) {
    const double y = std::clamp(lanes[i % 4], -w + 0.3, w - 0.3);
    people_.push_back({y, uniform_(rng_) * 2.0 * (walk_x1_ - walk_x0_) / kWalkSpeedMS});
  }
}

Eigen::AlignedBox3d SceneArtefacts::personAt(const Person& p, int64_t utime) const {
  // To and fro between walk_x0_ and walk_x1_: a triangle wave.
  const double span = walk_x1_ - walk_x0_;
  const double s = std::fmod(kWalkSpeedMS * (1e-6 * double(utime) + p.phase_s), 2.0 * span);
  const double x = walk_x0_ + (s < span ? s : 2.0 * span - s);
  return Eigen::AlignedBox3d(Eigen::Vector3d(x - 0.25, p.y_m - 0.15, 0.0),
                             Eigen::Vector3d(x + 0.25, p.y_m + 0.15, 1.75));
}

std::optional<double> SceneArtefacts::raycastObjects(const Eigen::Vector3d& origin,
                                                     const Eigen::Vector3d& dir, double limit_m,
                                                     int64_t utime, ObjectHit* what) const {
  std::optional<double> best;
  const auto take = [&](const Eigen::AlignedBox3d& box, double reflectivity) {
    int axis = 0;
    const auto t = rayBox(origin, dir, box, best.value_or(limit_m), &axis);
    if (!t) return;
    best = t;
    if (what) *what = {axis, reflectivity};
  };
  if (whiteboard_) take(*whiteboard_, kWhiteboardReflectivity);
  for (const Person& p : people_) take(personAt(p, utime), kPersonReflectivity);
  return best;
}

bool SceneArtefacts::returns(const Eigen::Vector3d& point, const Eigen::Vector3d& dir,
                             const Scene::Hit& hit) {
  const SceneBox& box = scene_->boxes()[hit.box];
  if (window_xz_ && box.name == "wall_y_min" && hit.axis == 1 &&
      window_xz_->contains(Eigen::Vector2d(point.x(), point.z()))) {
    return false;
  }
  if (dark_[hit.box] && sim_.dropout_dark_probability > 0 &&
      uniform_(rng_) < sim_.dropout_dark_probability) {
    return false;
  }
  const double incidence_deg = std::acos(std::min(1.0, std::fabs(dir[hit.axis]))) * kRadToDeg;
  return !glancingDropout(incidence_deg, sim_.dropout_glancing_probability, rng_);
}

void SceneArtefacts::mixEdges(std::vector<double>* ranges) {
  // A lidar's beam is wide (mrad): a jump of the true range between neighbouring rays is an
  // edge.
  const auto jump = [](const std::vector<double>& r, size_t i, size_t j) {
    return std::fabs(r[j] - r[i]) > kEdgeJumpM;
  };
  sweepmap::mixEdges(ranges, jump, sim_.mixed_pixel_probability, rng_);
}

}  // namespace sweepmap
