// The simulated rig C live (Zhao 2021): one simulated world -- the turntable's true motion
// as commanded, the scene, and the profile sensor's physics (SimProfiler::profile, the same
// code as the offline simulation's) -- behind the device interfaces a real driver will
// implement: SimTurntable (TurntableDevice) and SimProfilerDevice (ProfilerDevice).
//
// The turntable stands at turntable.sweep_start_deg at `start_utime` and moves to each
// commanded angle at the commanded speed (a precision servo: no ramps), then stands. The
// operator of the calibration (the scenes): plate pose 0 is in place at the start, and the
// next pose is put in place each time the table comes back to sweep_start_deg from elsewhere
// (the last pose stays); the test piece stays. Each placement is a truth event (its time,
// its index = the sweep that will see it).
//
// The encoder reads the true angle quantised (TurntableDevice samples every 10 ms from the
// start); the profiler exposes at profile.profile_rate_hz from the start, latching the
// encoder with SimProfiler's noise. Deterministic from the seed and the start time.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "devices/profiler_device.hpp"
#include "devices/turntable_device.hpp"
#include "sim/profiler.hpp"

namespace sweepmap {

// The scenes of sim.scene, one per sweep: the plate in each of its sim.plate_count poses (also
// returned in `plates`), or the test piece once. Throws std::invalid_argument for another
// scene name.
std::vector<ProfileScene> simProfileScenes(const SimProfileConfig& sim,
                                           const TurntableConfig& turntable,
                                           std::vector<PlatePose>* plates);

class SimProfileWorld {
 public:
  // Throws std::invalid_argument for a scene it cannot simulate.
  SimProfileWorld(const ProfilerConfig& profiler, const TurntableConfig& turntable,
                  const SimProfileConfig& sim, uint64_t seed, int64_t start_utime);

  void command(int64_t now_utime, const TurntableCommand& cmd);
  // The true encoder angle [deg] (before the zero) at `utime` (>= the last command's time).
  double encoderDegAt(int64_t utime) const;
  // The scene in place at `utime` (its index: see above).
  int sceneIndexAt(int64_t utime) const;
  // Placements (time, scene index) up to `now_utime` not yet taken, in order.
  std::vector<std::pair<int64_t, int>> takePlacements(int64_t now_utime);
  // The plate of scene k, nullptr for the test piece.
  const PlatePose* plate(int k) const;
  const ProfileScene& scene(int k) const { return scenes_.at(static_cast<size_t>(k)); }
  Profile expose(int64_t utime);

  const ProfilerConfig& profiler() const { return profiler_; }
  const TurntableConfig& turntable() const { return turntable_; }
  const SimProfileConfig& sim() const { return sim_; }
  int64_t startUtime() const { return start_utime_; }

 private:
  ProfilerConfig profiler_;
  TurntableConfig turntable_;
  SimProfileConfig sim_;
  SimProfiler physics_;
  std::vector<PlatePose> plates_;
  std::vector<ProfileScene> scenes_;
  int64_t start_utime_;
  // The motion: each command's, from angle0 at t0 toward target at speed (kept for
  // exposures polled after a later command).
  struct Segment {
    int64_t t0;
    double angle0_deg, target_deg, speed_deg_s;
  };
  std::vector<Segment> segments_;
  std::vector<int64_t> placements_;  // utime of scene k's placement, k >= 1 (scene 0: start)
  size_t placements_taken_ = 0;      // of 1 + placements_.size()
};

class SimTurntable : public TurntableDevice {
 public:
  static constexpr int64_t kSamplePeriodUs = 10000;
  explicit SimTurntable(SimProfileWorld* world) : world_(world) {}
  void command(int64_t now_utime, const TurntableCommand& cmd) override;
  std::vector<EncoderSample> poll(int64_t now_utime) override;
  int countsPerRevolution() const override;

 private:
  SimProfileWorld* world_;
  int64_t next_ = 0;  // sample index
};

class SimProfilerDevice : public ProfilerDevice {
 public:
  explicit SimProfilerDevice(SimProfileWorld* world) : world_(world) {}
  std::vector<Profile> poll(int64_t now_utime) override;

 private:
  SimProfileWorld* world_;
  int64_t next_ = 0;  // exposure index
};

}  // namespace sweepmap
