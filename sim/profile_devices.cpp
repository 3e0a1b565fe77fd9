#include "sim/profile_devices.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sweepmap {

std::vector<ProfileScene> simProfileScenes(const SimProfileConfig& sim,
                                           const TurntableConfig& turntable,
                                           std::vector<PlatePose>* plates) {
  std::vector<ProfileScene> scenes;
  plates->clear();
  if (sim.scene == "plate") {
    *plates = platePoses(sim, turntable);
    for (const PlatePose& p : *plates) scenes.push_back(ProfileScene::plate(p));
  } else if (sim.scene == "test_piece") {
    scenes.push_back(ProfileScene::testPiece(sim, turntable));
  } else {
    throw std::invalid_argument("sim.scene '" + sim.scene + "' is not plate or test_piece");
  }
  return scenes;
}

SimProfileWorld::SimProfileWorld(const ProfilerConfig& profiler, const TurntableConfig& turntable,
                                 const SimProfileConfig& sim, uint64_t seed, int64_t start_utime)
    : profiler_(profiler),
      turntable_(turntable),
      sim_(sim),
      physics_(profiler, turntable, sim, seed),
      scenes_(simProfileScenes(sim, turntable, &plates_)),
      start_utime_(start_utime) {
  segments_.push_back({start_utime, turntable.sweep_start_deg, turntable.sweep_start_deg, 0.0});
}

void SimProfileWorld::command(int64_t now_utime, const TurntableCommand& cmd) {
  if (!std::isfinite(cmd.target_deg) || !(cmd.speed_deg_s > 0) || !std::isfinite(cmd.speed_deg_s)) {
    throw std::invalid_argument("turntable command: target not finite or speed not > 0");
  }
  const double from = encoderDegAt(now_utime);
  segments_.push_back({now_utime, from, cmd.target_deg, cmd.speed_deg_s});
  // A move interrupted before it arrived put no plate in place.
  while (!placements_.empty() && placements_.back() > now_utime) placements_.pop_back();
  const double start = turntable_.sweep_start_deg;
  if (std::fabs(cmd.target_deg - start) < 1e-9 && std::fabs(from - start) > 1e-9) {
    placements_.push_back(now_utime + static_cast<int64_t>(std::ceil(std::fabs(start - from) /
                                                                     cmd.speed_deg_s * 1e6)));
  }
}

double SimProfileWorld::encoderDegAt(int64_t utime) const {
  auto it = std::upper_bound(segments_.begin(), segments_.end(), utime,
                             [](int64_t t, const Segment& s) { return t < s.t0; });
  const Segment& s = it == segments_.begin() ? segments_.front() : *(it - 1);
  const double delta = s.target_deg - s.angle0_deg;
  const double travel = s.speed_deg_s * std::max<int64_t>(0, utime - s.t0) * 1e-6;
  if (travel >= std::fabs(delta)) return s.target_deg;
  return s.angle0_deg + std::copysign(travel, delta);
}

int SimProfileWorld::sceneIndexAt(int64_t utime) const {
  const auto placed =
      std::upper_bound(placements_.begin(), placements_.end(), utime) - placements_.begin();
  return static_cast<int>(std::min<int64_t>(placed, static_cast<int64_t>(scenes_.size()) - 1));
}

std::vector<std::pair<int64_t, int>> SimProfileWorld::takePlacements(int64_t now_utime) {
  std::vector<std::pair<int64_t, int>> out;
  while (placements_taken_ < scenes_.size()) {
    const int64_t t = placements_taken_ == 0                    ? start_utime_
                      : placements_taken_ <= placements_.size() ? placements_[placements_taken_ - 1]
                                                                : INT64_MAX;
    if (t > now_utime) break;
    out.emplace_back(t, static_cast<int>(placements_taken_++));
  }
  return out;
}

const PlatePose* SimProfileWorld::plate(int k) const {
  return k >= 0 && k < static_cast<int>(plates_.size()) ? &plates_[static_cast<size_t>(k)]
                                                        : nullptr;
}

Profile SimProfileWorld::expose(int64_t utime) {
  const ProfileScene& scene = scenes_[static_cast<size_t>(sceneIndexAt(utime))];
  return physics_.profile(scene, encoderDegAt(utime) * (M_PI / 180.0), utime, 0);
}

void SimTurntable::command(int64_t now_utime, const TurntableCommand& cmd) {
  world_->command(now_utime, cmd);
}

int SimTurntable::countsPerRevolution() const { return world_->turntable().counts_per_revolution; }

std::vector<EncoderSample> SimTurntable::poll(int64_t now_utime) {
  std::vector<EncoderSample> out;
  const int cpr = countsPerRevolution();
  for (int64_t t = world_->startUtime() + next_ * kSamplePeriodUs; t <= now_utime;
       t = world_->startUtime() + ++next_ * kSamplePeriodUs) {
    out.push_back({t, static_cast<int64_t>(std::llround(world_->encoderDegAt(t) / 360.0 * cpr))});
  }
  return out;
}

std::vector<Profile> SimProfilerDevice::poll(int64_t now_utime) {
  std::vector<Profile> out;
  const double rate = world_->profiler().profile_rate_hz;
  const auto at = [&](int64_t k) {
    return world_->startUtime() + static_cast<int64_t>(std::llround(k * 1e6 / rate));
  };
  for (int64_t t = at(next_); t <= now_utime; t = at(++next_)) out.push_back(world_->expose(t));
  return out;
}

}  // namespace sweepmap
