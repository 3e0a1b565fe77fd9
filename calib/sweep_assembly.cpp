#include "calib/sweep_assembly.hpp"

#include <cmath>

#include "calib/plate_model.hpp"
#include "calib/rotating_geometry.hpp"

namespace sweepmap {

AssembledSweep assembleSweep(const std::vector<Scan2D>& scans, const SweepWindow& window,
                             const RotatingLidarConfig& rig) {
  AssembledSweep out;
  out.window = window;
  out.scans = static_cast<int>(scans.size());
  out.alpha_rad = rig.plate.alpha_deg * M_PI / 180.0;
  if (scans.empty()) {
    out.reason = "no scans in the window";
    return out;
  }
  out.first_ray_utime = scans.front().utime;
  const double offset_x_m = rig.geometry.lidar_offset_x_mm * 1e-3;

  const PlateRegion region = PlateRegion::fromConfig(rig.plate);
  // Every ray meeting the plate plane in the region: for the ray-plane estimate and for
  // checking either estimate against the plate's shape.
  std::vector<PlateRay> plate_rays;
  size_t total = 0;
  bool intensities = true;  // every scan of the window has them
  for (const auto& s : scans) {
    total += s.ranges_m.size();
    intensities = intensities && s.intensities.size() == s.ranges_m.size();
  }
  out.points_Op.reserve(total);
  if (intensities) out.intensities.reserve(total);
  // R_L^O' (identity unless the rig's scan plane is tilted or its mirror offset).
  const bool rotated =
      rig.geometry.scan_plane_tilt_deg != 0.0 || rig.geometry.mirror_offset_deg != 0.0;
  const Eigen::Matrix3d R_L = rotating::lidarRotation(rig.geometry.scan_plane_tilt_deg * kDegToRad,
                                                      rig.geometry.mirror_offset_deg * kDegToRad);
  forEachSweepRay(scans, window.omega_rad_s, [&](const SweepRay& ray) {
    Eigen::Vector3d p_L = rotating::pointInLidar(ray.range_m, ray.theta_rad);
    if (rotated) p_L = R_L * p_L;
    const Eigen::Vector3d p_Op = rotating::lidarToOPrime(p_L, ray.phi_rad, offset_x_m);
    out.points_Op.push_back(p_Op.cast<float>());
    if (intensities) out.intensities.push_back(ray.intensity);
    const Eigen::Vector3d origin =
        rotating::lidarToOPrime(Eigen::Vector3d::Zero(), ray.phi_rad, offset_x_m);
    const Eigen::Vector3d dir = (p_Op - origin) / ray.range_m;
    if (plateRayRange(origin, dir, region)) plate_rays.push_back({origin, dir, ray.range_m});
  });

  out.plate_rays = std::move(plate_rays);
  correctSweep(rig, &out);
  return out;
}

void correctSweep(const RotatingLidarConfig& rig, AssembledSweep* sweep) {
  AssembledSweep& out = *sweep;
  const PlateRegion region = PlateRegion::fromConfig(rig.plate);
  out.alpha_rad = rig.plate.alpha_deg * M_PI / 180.0;
  if (rig.plate.beta_method == "model") {
    const PlateModelFit f =
        fitPlateModel(PlateModel::fromConfig(rig.plate), out.plate_rays, rig.plate.min_points);
    out.plate = PlateEstimate{f.found, f.hits, f.angle_rad, f.reason};
  } else {
    out.plate = rig.plate.beta_method == "ray_plane"
                    ? estimateBetaRayPlane(out.plate_rays, region, rig.plate.range_gate_mm * 1e-3,
                                           rig.plate.min_points)
                    : estimateBetaCentroid(out.points_Op, region, rig.plate.min_points);
  }
  out.plate_check = PlateCheck{};
  if (out.plate.found) {
    out.plate_check =
        checkPlate(out.plate_rays, region, out.plate.beta_rad, rig.plate.hypotenuse_mm * 1e-3,
                   rig.plate.base_distance_mm * 1e-3, rig.plate.range_gate_mm * 1e-3);
  }
  out.corrected = false;
  out.phi_offset_rad = 0.0;
  out.reason.clear();
  if (!rig.assembler.correct_attitude) {
    out.reason = "correction disabled (assembler.correct_attitude=false)";
  } else if (out.window.accel_overlap) {
    out.reason = "motor ramp overlapped the lidar window";
  } else if (!out.plate.found) {
    out.reason = out.plate.reason;
  } else if (!out.plate_check.problem.empty()) {
    out.reason = out.plate_check.problem;
  } else {
    out.corrected = true;
    out.phi_offset_rad = rotating::phiOffset(out.alpha_rad, out.plate.beta_rad);
  }
  out.points.clear();
  if (out.corrected) {
    const Eigen::Matrix3f R = rotating::rotZ(out.phi_offset_rad).cast<float>();
    out.points.reserve(out.points_Op.size());
    for (const auto& p : out.points_Op) out.points.push_back(R * p);
  } else {
    out.points = out.points_Op;
  }
}

void uncorrectSweep(const std::string& reason, AssembledSweep* sweep) {
  if (!sweep->corrected) return;
  sweep->corrected = false;
  sweep->phi_offset_rad = 0.0;
  sweep->reason = reason;
  sweep->points = sweep->points_Op;
}

}  // namespace sweepmap
