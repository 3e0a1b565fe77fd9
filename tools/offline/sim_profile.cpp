#include "tools/offline/sim_profile.hpp"

#include <cmath>

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/sim_setup.hpp"
#include "sim/profile_devices.hpp"

namespace sweepmap {

SimProfileResult simulateRotatingProfile(const RotatingProfileConfig& rig, uint64_t seed,
                                         const std::function<void(const Message&)>& sink) {
  SimProfiler profiler(rig.profiler, rig.turntable, rig.sim, seed);
  std::vector<PlatePose> plates;
  std::vector<ProfileScene> scenes;
  try {
    scenes = simProfileScenes(rig.sim, rig.turntable, &plates);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(e.what());
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
    out.publish(
        channels::kTruthProfileRig, start,
        makeTruthProfileRig(rig.sim, sweep_id, start, plates.empty() ? nullptr : &plates[k]));
    if (const auto frame = scenes[k].testPieceFrame()) {
      out.publish(channels::kTruthTestPiece, start,
                  makeTruthTestPiece(rig.sim.test_piece, *frame, sweep_id, start));
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
