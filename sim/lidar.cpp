#include "sim/lidar.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/angles.hpp"
#include "sim/reflectance.hpp"

namespace sweepmap {
namespace {

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

}  // namespace

std::vector<Eigen::Vector3d> SimLidar::plateVertices(const PlateConfig& plate, double alpha_rad) {
  const Eigen::Vector3d along(std::cos(alpha_rad), std::sin(alpha_rad), 0.0);  // middle line
  const Eigen::Vector3d across(-along.y(), along.x(), 0.0);
  const double half_hyp_m = plate.hypotenuse_mm / 2000.0;
  const Eigen::Vector3d mid =
      plate.base_distance_mm / 1000.0 * along + Eigen::Vector3d(0, 0, plate.height_mm / 1000.0);
  // Isosceles right triangle: the apex is half the hypotenuse from its midpoint.
  return {mid + half_hyp_m * across, mid - half_hyp_m * across, mid + half_hyp_m * along};
}

SimLidar::SimLidar(const LidarConfig& lidar, const SimRigConfig& sim, const PlateConfig& plate,
                   const Scene& scene, const ShaftTrajectory* truth, uint64_t seed,
                   int64_t first_scan_utime)
    : lidar_(lidar),
      offset_m_(sim.lidar_offset_x_mm / 1000.0),
      noise_sigma_m_(sim.range_noise_sigma_mm / 1000.0),
      latency_us_(std::llround(sim.lidar_latency_ms * 1000.0)),
      time_increment_ns_(std::llround(lidar.rayPeriodS() * 1e9)),
      scene_(&scene),
      truth_(truth),
      T_room_rig_(scene.T_room_rig()),
      plate_z_m_(plate.height_mm / 1000.0),
      plate_thickness_m_(sim.plate_thickness_mm / 1000.0),
      plate_base_m_(plate.base_distance_mm / 1000.0),
      plate_half_m_(plate.hypotenuse_mm / 2000.0),
      artefacts_(sim, scene, seed),
      rng_(seed),
      first_scan_utime_(first_scan_utime) {
  if (truth == nullptr) throw std::invalid_argument("SimLidar: no truth trajectory");
  if (lidar.beam_count < 1 || !(lidar.scan_rate_hz > 0.0) || lidar.steps_per_revolution < 1) {
    throw std::invalid_argument(
        "SimLidar: lidar.beam_count, scan_rate_hz and steps_per_revolution must be positive");
  }
  if (!(lidar.range_min_m >= 0.0 && lidar.range_min_m < lidar.range_max_m)) {
    throw std::invalid_argument("SimLidar: need 0 <= lidar.range_min_m < lidar.range_max_m");
  }
  if (!(noise_sigma_m_ >= 0.0) || latency_us_ < 0) {
    throw std::invalid_argument(
        "SimLidar: sim.range_noise_sigma_mm and sim.lidar_latency_ms must be >= 0");
  }
  const auto corners = plateVertices(plate, sim.alpha_true_deg * kDegToRad);
  for (size_t k = 0; k < 3; ++k) plate_xy_[k] = corners[k].head<2>();
  plate_along_ = Eigen::Vector2d(std::cos(sim.alpha_true_deg * kDegToRad),
                                 std::sin(sim.alpha_true_deg * kDegToRad));
  plate_across_ = Eigen::Vector2d(-plate_along_.y(), plate_along_.x());
  if (!(plate_thickness_m_ >= 0.0)) {
    throw std::invalid_argument("SimLidar: sim.plate_thickness_mm must be >= 0");
  }
  for (const SceneBox& b : scene.boxes()) reflectivity_.push_back(surfaceReflectivity(b.name));
  const double tilt = sim.scan_plane_tilt_deg * kDegToRad;
  for (int i = 0; i < lidar.beam_count; ++i) {
    const double theta =
        (lidar.angle_min_deg + i * lidar.angle_increment_deg + sim.mirror_offset_deg) * kDegToRad;
    sin_theta_.push_back(std::sin(theta));
    cos_theta_.push_back(std::cos(tilt) * std::cos(theta));
    dir_x_.push_back(std::sin(tilt) * std::cos(theta));
  }
}

int64_t SimLidar::scanUtime(int64_t index) const {
  return first_scan_utime_ + std::llround(double(index) * 1e6 / lidar_.scan_rate_hz);
}

std::vector<Scan2D> SimLidar::poll(int64_t now_utime) {
  const int64_t last_ray_us = (time_increment_ns_ * (lidar_.beam_count - 1)) / 1000;
  std::vector<Scan2D> scans;
  for (;;) {
    const int64_t utime = scanUtime(next_index_);
    if (utime + last_ray_us + latency_us_ > now_utime) break;
    if (truth_->covers(utime)) {
      scans.push_back(makeScan(next_index_, utime));
    } else {
      ++skipped_scans_;
    }
    ++next_index_;
  }
  return scans;
}

Scan2D SimLidar::makeScan(int64_t index, int64_t utime) {
  Scan2D scan;
  scan.utime = utime;
  scan.seq = index;
  scan.angle_min_rad = lidar_.angle_min_deg * kDegToRad;
  scan.angle_increment_rad = lidar_.angle_increment_deg * kDegToRad;
  scan.time_increment_ns = time_increment_ns_;
  scan.range_min_m = lidar_.range_min_m;
  scan.range_max_m = lidar_.range_max_m;
  scan.ranges_m.resize(size_t(lidar_.beam_count));

  // Nothing beyond this can come back inside range_max, whatever the noise.
  const double cast_range_m = lidar_.range_max_m + 6.0 * noise_sigma_m_;
  std::vector<float> intensity;
  std::vector<double> hits = trueRanges(utime, cast_range_m, &intensity);
  artefacts_.mixEdges(&hits);
  scan.intensities.resize(scan.ranges_m.size());
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double noisy_m = hits[i] + noise_sigma_m_ * standard_normal_(rng_);
    const bool valid =
        hits[i] != 0.0 && noisy_m >= lidar_.range_min_m && noisy_m <= lidar_.range_max_m;
    scan.ranges_m[i] = valid ? float(noisy_m) : 0.0f;
    scan.intensities[i] = valid ? intensity[i] : 0.0f;
  }
  return scan;
}

std::vector<double> SimLidar::trueRanges(int64_t utime, double cast_range_m,
                                         std::vector<float>* intensity) {
  std::vector<double> hits(size_t(lidar_.beam_count), 0.0);
  intensity->assign(hits.size(), 0.0f);
  Scan2D timing;
  timing.utime = utime;
  timing.time_increment_ns = time_increment_ns_;
  int64_t shaft_utime = utime - 1;  // shaft angle cached per microsecond
  double cos_phi = 0.0, sin_phi = 0.0;
  for (size_t i = 0; i < hits.size(); ++i) {
    const int64_t ray_utime = timing.rayUtime(i);
    if (ray_utime != shaft_utime) {
      const double phi = truth_->angleAt(ray_utime);
      cos_phi = std::cos(phi);
      sin_phi = std::sin(phi);
      shaft_utime = ray_utime;
    }
    // Eq. 4-6 with the true shaft angle and R_L^O' of the build: frame L turned by Rz(phi).
    const Eigen::Vector3d origin_o(cos_phi * offset_m_, sin_phi * offset_m_, 0.0);
    const Eigen::Vector3d dir_o(cos_phi * dir_x_[i] - sin_phi * sin_theta_[i],
                                sin_phi * dir_x_[i] + cos_phi * sin_theta_[i], cos_theta_[i]);
    const RayHit hit = castRay(origin_o, dir_o, cast_range_m, ray_utime);
    hits[i] = hit.range_m;
    (*intensity)[i] = simulatedIntensity(hit.reflectivity, hit.cos_incidence, hit.range_m);
  }
  return hits;
}

SimLidar::RayHit SimLidar::castRay(const Eigen::Vector3d& origin_o, const Eigen::Vector3d& dir_o,
                                   double cast_range_m, int64_t ray_utime) {
  const Eigen::Vector3d origin_room = T_room_rig_ * origin_o;
  const Eigen::Vector3d dir_room = T_room_rig_.linear() * dir_o;
  RayHit out;
  Scene::Hit what;
  std::optional<double> hit = scene_->raycast(origin_room, dir_room, cast_range_m, &what);
  if (hit && !artefacts_.returns(origin_room + *hit * dir_room, dir_room, what)) hit = 0.0;
  if (hit && *hit > 0.0) {
    out.reflectivity = reflectivity_[what.box];
    out.cos_incidence = dir_room[what.axis];
  }
  const double limit_m = hit && *hit > 0.0 ? *hit : cast_range_m;
  SceneArtefacts::ObjectHit object;
  if (const auto obj =
          artefacts_.raycastObjects(origin_room, dir_room, limit_m, ray_utime, &object)) {
    hit = obj;
    out.reflectivity = object.reflectivity;
    out.cos_incidence = dir_room[object.axis];
  }
  if (const auto plate = hitPlate(origin_o, dir_o);
      plate && (!hit || *hit == 0.0 || *plate < *hit)) {
    hit = plate;
    out.reflectivity = kPlateReflectivity;
    // Its upper surface (normal Z of frame O), else the face of its hypotenuse.
    const bool on_top = std::fabs(origin_o.z() + *plate * dir_o.z() - plate_z_m_) < 1e-9;
    out.cos_incidence = on_top ? dir_o.z() : plate_along_.dot(dir_o.head<2>());
  }
  out.range_m = hit.value_or(0.0);
  return out;
}

std::optional<double> SimLidar::hitPlate(const Eigen::Vector3d& origin_o,
                                         const Eigen::Vector3d& dir_o) const {
  if (dir_o.z() == 0.0) return std::nullopt;
  const double t = (plate_z_m_ - origin_o.z()) / dir_o.z();
  if (!(t > 0.0)) return std::nullopt;
  const Eigen::Vector2d p = (origin_o + t * dir_o).head<2>();
  const double d0 = cross2(plate_xy_[1] - plate_xy_[0], p - plate_xy_[0]);
  const double d1 = cross2(plate_xy_[2] - plate_xy_[1], p - plate_xy_[1]);
  const double d2 = cross2(plate_xy_[0] - plate_xy_[2], p - plate_xy_[2]);
  const bool inside = (d0 >= 0 && d1 >= 0 && d2 >= 0) || (d0 <= 0 && d1 <= 0 && d2 <= 0);
  if (inside) return t;
  // The face of the hypotenuse (the edge toward the axis), plate_thickness_m_ tall below the
  // upper surface: a ray passing just inside the edge, going outward and down, ends on it.
  const double out = plate_along_.dot(dir_o.head<2>());
  if (!(plate_thickness_m_ > 0.0) || !(out > 0.0)) return std::nullopt;
  const double tf = (plate_base_m_ - plate_along_.dot(origin_o.head<2>())) / out;
  if (!(tf > 0.0)) return std::nullopt;
  const Eigen::Vector3d q = origin_o + tf * dir_o;
  const double across = plate_across_.dot(q.head<2>());
  const bool on_face = q.z() <= plate_z_m_ && q.z() >= plate_z_m_ - plate_thickness_m_ &&
                       std::fabs(across) <= plate_half_m_;
  if (!on_face) return std::nullopt;
  return tf;
}

}  // namespace sweepmap
