#include "tools/offline/sim_profile.hpp"

#include <cmath>

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/sim_setup.hpp"
#include "sweepmap/truth_profile_rig_t.hpp"
#include "sweepmap/truth_test_piece_t.hpp"

namespace sweepmap {

namespace {

truth_profile_rig_t truthMessage(const SimProfileConfig& sim, int32_t sweep_id, int64_t utime,
                                 const PlatePose* plate) {
  const ProfileGeometry g = sim.trueGeometry();
  truth_profile_rig_t t{};
  t.utime = utime;
  t.sweep_id = sweep_id;
  t.offset_m_mm = g.m_mm;
  t.offset_n_mm = g.n_mm;
  t.laser_tilt_rad = g.laser_tilt_rad;
  t.encoder_zero_rad = g.encoder_zero_rad;
  t.range_noise_sigma_mm = sim.range_noise_sigma_mm;
  t.encoder_noise_counts = sim.encoder_noise_counts;
  t.scene = sim.scene;
  t.has_plane = plate != nullptr;
  if (plate) {
    for (int i = 0; i < 3; ++i) t.plane_normal[i] = plate->normal[i];
    t.plane_distance_mm = plate->distance();
  }
  return t;
}

// The test piece's true sizes and frame (what Zhao 2021's CMM measured).
truth_test_piece_t testPieceMessage(const TestPieceConfig& c, const ProfileScene::Frame& f,
                                    int32_t sweep_id, int64_t utime) {
  truth_test_piece_t t{};
  t.utime = utime;
  t.sweep_id = sweep_id;
  for (int i = 0; i < 3; ++i) {
    t.origin[i] = f.origin[i];
    t.u_axis[i] = f.u[i];
    t.v_axis[i] = f.v[i];
    t.w_axis[i] = f.w[i];
  }
  t.block_length_mm = c.block_length_mm;
  t.block_width_mm = c.block_width_mm;
  t.spacing_mm = c.spacing_mm;
  t.left_diameter_mm = c.left_diameter_mm;
  t.left_depth_mm = c.left_depth_mm;
  t.right_diameter_mm = c.right_diameter_mm;
  t.right_depth_mm = c.right_depth_mm;
  t.rect_length_mm = c.rect_length_mm;
  t.rect_width_mm = c.rect_width_mm;
  t.rect_depth_mm = c.rect_depth_mm;
  return t;
}

}  // namespace

SimProfileResult simulateRotatingProfile(const RotatingProfileConfig& rig, uint64_t seed,
                                         const std::function<void(const Message&)>& sink) {
  SimProfiler profiler(rig.profiler, rig.turntable, rig.sim, seed);
  std::vector<ProfileScene> scenes;
  std::vector<PlatePose> plates;
  if (rig.sim.scene == "plate") {
    plates = platePoses(rig.sim, rig.turntable);
    for (const PlatePose& p : plates) scenes.push_back(ProfileScene::plate(p));
  } else if (rig.sim.scene == "test_piece") {
    scenes.push_back(ProfileScene::testPiece(rig.sim, rig.turntable));
  } else {
    throw ConfigError("sim.scene '" + rig.sim.scene + "' is not plate or test_piece");
  }
  SimProfileResult result;
  int64_t start = kSimEpochUtime;
  const auto emit = [&](const Message& m) {
    ++result.messages;
    sink(m);
  };
  for (size_t k = 0; k < scenes.size(); ++k) {
    const auto sweep_id = static_cast<int32_t>(k);
    Outbox out;
    out.publish(channels::kTruthProfileRig, start,
                truthMessage(rig.sim, sweep_id, start, plates.empty() ? nullptr : &plates[k]));
    if (const auto frame = scenes[k].testPieceFrame()) {
      out.publish(channels::kTruthTestPiece, start,
                  testPieceMessage(rig.sim.test_piece, *frame, sweep_id, start));
    }
    for (const Profile& p : profiler.sweep(scenes[k], sweep_id, start)) {
      out.publish(channels::kProfile, p.utime, toLcm(p));
      ++result.profiles;
      result.points += static_cast<int64_t>(p.column.size());
    }
    for (auto& m : out.take()) emit(m);
    ++result.sweeps;
    start += profiler.sweepDurationUs() + static_cast<int64_t>(std::llround(rig.sim.pause_s * 1e6));
  }
  result.duration_s = (start - kSimEpochUtime) / 1e6;
  return result;
}

}  // namespace sweepmap
