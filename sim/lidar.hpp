// Simulated 2D lidar (Hokuyo UST-10LX) turned by the simulated shaft (rig A, Yuan 2021
// Eq. 4-6).
//
// Frame O: the rig frame, origin on the rotation axis at the lidar centre's height, Z the
// rotation axis (up). With phi the true shaft angle at a ray's time and theta the ray's
// angle in the scan (from Z_L toward Y_L), the ray starts at Rz(phi) (offset, 0, 0) and
// points along Rz(phi) (0, sin theta, cos theta), offset = sim.lidar_offset_x_mm. The
// scene is placed with Scene::T_room_rig(); the triangular plate is fixed in frame O at
// its true angle sim.alpha_true_deg.
//
// Timing: scan j starts at first_scan_utime + round(j * 1e6 / scan_rate_hz) us; ray i is
// at Scan2D::rayUtime(i); the scan is delivered sim.lidar_latency_ms after its last ray.
// Range noise N(0, sim.range_noise_sigma_mm) from one std::mt19937_64(seed), one draw per
// ray in order; a noisy range outside [range_min_m, range_max_m], or no hit, reads 0.
// Intensity (SCIP ME's reflectance): sim/reflectance.hpp's model of the surface hit, from the
// true range and the incidence; 0 where the range reads 0. Deterministic, no random draw.
//
// A real build (sim.*, 0 in the paper's model): the ray leaves along
// Ry(tilt) (0, sin(theta + mirror), cos(theta + mirror)) in frame L (tilt =
// sim.scan_plane_tilt_deg about Y_L, mirror = sim.mirror_offset_deg about X_L); the plate is a
// solid sim.plate_thickness_mm thick below its upper surface, so rays that pass just inside its
// hypotenuse end on that edge's face; the scene's artefacts are sim/artefacts.hpp's.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

#include "core/rig_components.hpp"
#include "devices/lidar_device.hpp"
#include "devices/shaft_trajectory.hpp"
#include "sim/artefacts.hpp"
#include "sim/scene.hpp"

namespace sweepmap {

class SimLidar : public LidarDevice {
 public:
  // `scene` and `truth` must outlive the lidar; `truth` may grow while the lidar runs.
  // Throws std::invalid_argument for a lidar or noise configuration it cannot simulate.
  SimLidar(const LidarConfig& lidar, const SimRigConfig& sim, const PlateConfig& plate,
           const Scene& scene, const ShaftTrajectory* truth, uint64_t seed,
           int64_t first_scan_utime);

  // Every scan delivered by `now_utime` (last ray + latency), in order, seq = scan index.
  // Scans that start before the truth covers them are skipped (counted).
  std::vector<Scan2D> poll(int64_t now_utime) override;
  int64_t skippedScans() const { return skipped_scans_; }

  // Plate corners in frame O [m]: the two ends of the hypotenuse, then the right-angle apex.
  // The plate lies in z = plate.height_mm; its middle line is at alpha_rad from X.
  static std::vector<Eigen::Vector3d> plateVertices(const PlateConfig& plate, double alpha_rad);

 private:
  int64_t scanUtime(int64_t index) const;
  Scan2D makeScan(int64_t index, int64_t utime);
  // The true range of every ray of a scan starting at `utime` (0: no return), and each ray's
  // intensity (sim/reflectance.hpp; 0: no return).
  std::vector<double> trueRanges(int64_t utime, double cast_range_m, std::vector<float>* intensity);
  // One ray (frame O) against the scene, its artefacts and the plate: the nearest return.
  struct RayHit {
    double range_m = 0.0;  // 0: no return
    double reflectivity = 0.0;
    double cos_incidence = 0.0;  // the ray's direction against the surface's normal
  };
  RayHit castRay(const Eigen::Vector3d& origin_o, const Eigen::Vector3d& dir_o, double cast_range_m,
                 int64_t ray_utime);
  // Distance along the ray (frame O) to the plate, if it hits.
  std::optional<double> hitPlate(const Eigen::Vector3d& origin_o,
                                 const Eigen::Vector3d& dir_o) const;

  LidarConfig lidar_;
  double offset_m_;
  double noise_sigma_m_;
  int64_t latency_us_;
  int64_t time_increment_ns_;
  const Scene* scene_;
  const ShaftTrajectory* truth_;
  Eigen::Isometry3d T_room_rig_;
  double plate_z_m_;
  double plate_thickness_m_;
  std::array<Eigen::Vector2d, 3> plate_xy_;     // plate corners in frame O's XY plane
  Eigen::Vector2d plate_along_, plate_across_;  // unit: the middle line, the hypotenuse
  double plate_base_m_, plate_half_m_;
  // Per ray: the direction in frame L, (sin tilt cos theta', sin theta', cos tilt cos theta')
  // with theta' = theta + mirror offset.
  std::vector<double> dir_x_, sin_theta_, cos_theta_;
  SceneArtefacts artefacts_;
  std::vector<double> reflectivity_;  // of each scene box (sim/reflectance.hpp)
  std::mt19937_64 rng_;
  std::normal_distribution<double> standard_normal_;
  int64_t first_scan_utime_;
  int64_t next_index_ = 0;
  int64_t skipped_scans_ = 0;
};

}  // namespace sweepmap
