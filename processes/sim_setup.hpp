// Pieces of the simulated rig shared by `sweepmap sim` and the live processes in --sim mode.
#pragma once

#include <cstdint>

#include "rigs/rotating_lidar.hpp"
#include "sim/profiler.hpp"
#include "sim/scene.hpp"
#include "sweepmap/truth_profile_rig_t.hpp"
#include "sweepmap/truth_rig_errors_t.hpp"
#include "sweepmap/truth_rig_t.hpp"
#include "sweepmap/truth_test_piece_t.hpp"

namespace sweepmap {

// The shaft's angle when the simulated rig powers up (unknown to the controller).
constexpr double kSimInitialShaftAngleRad = 0.8;
// Time origin of offline simulation (virtual clock) [us]: 2023-11-14T22:13:20Z.
constexpr int64_t kSimEpochUtime = 1700000000000000LL;

// Independent random streams of the simulated devices, derived from one seed.
inline uint64_t stepperSeed(uint64_t seed) { return seed * 2 + 1; }
inline uint64_t lidarSeed(uint64_t seed) { return seed * 2 + 2; }

truth_rig_t makeTruthRig(const RotatingLidarConfig& rig, const SceneConfig& scene_config,
                         const Scene& scene, int64_t utime);
// The build's errors and the scene's artefacts (TRUTH_RIG_ERRORS), published beside it.
truth_rig_errors_t makeTruthRigErrors(const SimRigConfig& sim, int64_t utime);

// The scene's artefacts into a truth message of rig A (truth_rig_errors_t) or rig B
// (truth_mobile_rig_t): their fields have the names of the sim.* keys.
template <class TruthMessage>
void setArtefactTruth(const SceneArtefactConfig& sim, TruthMessage* m) {
  m->mixed_pixel_probability = sim.mixed_pixel_probability;
  m->dropout_dark_probability = sim.dropout_dark_probability;
  m->dropout_glancing_probability = sim.dropout_glancing_probability;
  m->people = sim.people;
  m->window_width_m = sim.window_width_m;
  m->whiteboard_proud_m = sim.whiteboard_proud_mm * 1e-3;
}

// Rig C's truth (TRUTH_PROFILE_RIG) for sweep `sweep_id`, with the plate's true plane when
// `plate` is given: what the offline simulation and the live simulated profiler publish.
truth_profile_rig_t makeTruthProfileRig(const SimProfileConfig& sim, int32_t sweep_id,
                                        int64_t utime, const PlatePose* plate);
// The test piece's true sizes (what Zhao 2021's CMM measured) and its frame in O_r.
truth_test_piece_t makeTruthTestPiece(const TestPieceConfig& c, const ProfileScene::Frame& f,
                                      int32_t sweep_id, int64_t utime);

}  // namespace sweepmap
