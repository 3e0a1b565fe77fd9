// The real-scene artefacts a calibration must survive, for the simulated lidars of rig A and
// rig B (sim.* keys of SceneArtefactConfig; all 0 in the paper experiments):
//  - mixed pixels: a ray at a depth edge (its neighbour's range differs by more than 50 mm)
//    returns, with probability sim.mixed_pixel_probability, a range uniformly between the two;
//  - dropouts: no return from dark furniture (table, cabinet) with probability
//    sim.dropout_dark_probability, and at grazing incidence with a probability rising linearly
//    from 0 at 70 deg to sim.dropout_glancing_probability at 90 deg;
//  - sim.people people (0.5 x 0.3 x 1.75 m boxes) walking to and fro along X at 1 m/s;
//  - a window sim.window_width_m wide (1.2 m high, sill 0.9 m, centred at room x = -1 m) in the
//    -Y wall: glass, no return;
//  - a whiteboard (2 x 1.2 m, bottom 0.9 m, centred at room y = 0.5 m) sim.whiteboard_proud_mm
//    proud of the -X wall, or of the +X wall where the scene's calibration target (rig B's
//    lab) is on the -X wall.
// Randomness: one std::mt19937_64 of its own (seed mixed), drawn only where an artefact applies,
// so a rig without artefacts draws nothing and simulates exactly as before them. reseed()
// restarts it (a scan made on its own, as the emulator makes them, draws what it draws in a
// whole run); the people's walks stay those of the constructor's seed.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

#include "core/rig_components.hpp"
#include "sim/scene.hpp"

namespace sweepmap {

// The artefacts' physics, shared by the lidars' rooms (SceneArtefacts) and rig C's profiler
// (sim/profiler.hpp); each draws from `rng` only where its artefact applies.
//
// Mixed pixels over one scan's or profile's true ranges (0: no return), in ray order, in
// place: a ray at a depth edge with a neighbour (`edge(true_ranges, i, j)`: rays i and j meet
// different surfaces, or one surface across a step) returns, with `probability`, a range
// uniformly between its own and that neighbour's (across the larger of its two edges).
template <class AtEdge>
void mixEdges(std::vector<double>* ranges, const AtEdge& edge, double probability,
              std::mt19937_64& rng) {
  if (!(probability > 0)) return;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const std::vector<double> r = *ranges;
  for (size_t i = 0; i < r.size(); ++i) {
    if (r[i] == 0.0) continue;
    double other = 0.0, jump = 0.0;  // the neighbour across the larger edge
    for (const size_t j : {i - 1, i + 1}) {
      if (j >= r.size() || r[j] == 0.0 || !edge(r, i, j) || !(std::fabs(r[j] - r[i]) > jump)) {
        continue;
      }
      other = r[j];
      jump = std::fabs(r[j] - r[i]);
    }
    if (other == 0.0 || uniform(rng) >= probability) continue;
    (*ranges)[i] = r[i] + uniform(rng) * (other - r[i]);
  }
}
// Whether a return at `incidence_deg` from the surface's normal is lost: never up to 70 deg,
// with a probability rising linearly to `at_90_deg` at 90 deg.
bool glancingDropout(double incidence_deg, double at_90_deg, std::mt19937_64& rng);

class SceneArtefacts {
 public:
  SceneArtefacts(const SceneArtefactConfig& sim, const Scene& scene, uint64_t seed);
  void reseed(uint64_t seed) { rng_.seed(seed ^ 0x9e3779b97f4a7c15ULL); }

  // Distance to the nearest artefact object (whiteboard, a person at `utime`) along the ray
  // (room frame, unit direction) within (0, limit_m), if any.
  // With `what`, set on a hit: the axis (0..2) of the face's normal and the object's diffuse
  // reflectivity (sim/reflectance.hpp).
  struct ObjectHit {
    int axis = 0;
    double reflectivity = 0.0;
  };
  std::optional<double> raycastObjects(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                       double limit_m, int64_t utime,
                                       ObjectHit* what = nullptr) const;
  // Whether a hit of the scene's box `hit` at `point` (room frame) returns (window, dark,
  // grazing incidence).
  bool returns(const Eigen::Vector3d& point, const Eigen::Vector3d& dir, const Scene::Hit& hit);
  // Mixed pixels over one scan's true ranges (0: no hit), in ray order, in place.
  void mixEdges(std::vector<double>* ranges);

 private:
  struct Person {
    double y_m, phase_s;
  };
  Eigen::AlignedBox3d personAt(const Person& p, int64_t utime) const;

  SceneArtefactConfig sim_;
  const Scene* scene_;
  std::optional<Eigen::AlignedBox3d> whiteboard_;
  std::optional<Eigen::AlignedBox2d> window_xz_;  // on the -Y wall
  std::vector<bool> dark_;                        // per scene box
  std::vector<Person> people_;
  double walk_x0_ = 0, walk_x1_ = 0;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
};

}  // namespace sweepmap
