#include "tools/offline/runs.hpp"

#include <sstream>
#include <type_traits>

#include "processes/sim_car.hpp"
#include "tools/offline/replay.hpp"
#include "tools/offline/replay_mobile.hpp"
#include "tools/offline/replay_profile.hpp"
#include "tools/offline/sim_mobile.hpp"
#include "tools/offline/sim_profile.hpp"
#include "tools/offline/simulation.hpp"

namespace sweepmap {

namespace {

// Lets std::visit take one lambda per rig kind.
template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace

SimSetup loadSimSetup(const std::string& rig, const std::string& scene,
                      const std::vector<std::string>& overrides) {
  std::vector<std::string> rig_sets, scene_sets;
  splitSimOverrides(overrides, &rig_sets, &scene_sets);
  SimSetup s;
  s.rig = loadRig(rig, rig_sets);
  if (auto* profile = std::get_if<RotatingProfileConfig>(&s.rig.config)) {
    // Rig C's scenes are built in (sim/profiler.hpp), sized by the rig's sim.* keys.
    if (!scene_sets.empty()) {
      throw ConfigError("scene." + scene_sets.front() + ": " + s.rig.path +
                        " is a rotating_profile rig: its scene is set by sim.* keys");
    }
    if (!scene.empty()) {
      if (scene != "plate" && scene != "test_piece") {
        throw ConfigError("--scene '" + scene +
                          "': a rotating_profile rig's scene is plate or "
                          "test_piece");
      }
      profile->sim.scene = scene;
    }
    s.scene_path = profile->sim.scene;
    return s;
  }
  s.scene_path = resolveConfigFile(scene.empty() ? defaultSceneName(s.rig.kind()) : scene);
  if (auto* mobile = std::get_if<MobileLidarConfig>(&s.rig.config)) {
    prepareSimMobileConfig(s.rig.path, mobile);
  }
  s.scene = loadScene(s.scene_path, scene_sets);
  return s;
}

void printSimConfig(std::ostream& out, const SimSetup& setup) {
  std::visit(
      [&](const auto& rig) {
        using Rig = std::decay_t<decltype(rig)>;
        Rig rig_copy = rig, rig_defaults{};
        ConfigSchema rs, rds;
        rig_copy.declare(rs);
        rig_defaults.declare(rds);
        out << "# rig (" << setup.rig.path << ", kind " << setup.rig.kindName() << ")\n";
        rs.print(out, &rds);
        if constexpr (std::is_same_v<Rig, RotatingProfileConfig>) {
          out << "# scene: sim.scene (" << setup.scene_path << "), sized by the sim.* keys\n";
        } else {
          SceneConfig scene = setup.scene, scene_defaults{};
          ConfigSchema ss, sds;
          scene.declare(ss, "scene.");
          scene_defaults.declare(sds, "scene.");
          out << "# scene (" << setup.scene_path << "), keys prefixed scene. for --set\n";
          ss.print(out, &sds);
        }
      },
      setup.rig.config);
}

SimRunResult simulateRig(const SimSetup& setup, const SimRunOptions& options,
                         const std::function<void(const Message&)>& sink) {
  return std::visit(
      Overloaded{
          [&](const RotatingLidarConfig& rig) {
            SimOptions o;
            o.rig = rig;
            o.scene = setup.scene;
            o.sweeps = options.sweeps;
            o.seed = options.seed;
            const SimResult r = simulate(o, sink);
            std::ostringstream line;
            line << r.sweeps_done << " sweeps in mode " << rig.motor.mode << ", "
                 << r.simulated_us / 1e6 << " s simulated, " << r.messages << " messages";
            if (r.motor_fault) line << "; the motor controller faulted (see STATUS_MOTOR)";
            return SimRunResult{!r.motor_fault && r.sweeps_done == options.sweeps, line.str()};
          },
          [&](const MobileLidarConfig& rig) {
            SimMobileOptions o;
            o.rig = rig;
            o.scene = setup.scene;
            o.seed = options.seed;
            const SimMobileResult r = simulateMobile(o, sink);
            std::ostringstream line;
            line << rig.sim.path << " path, " << r.duration_s << " s, " << r.path_length_m
                 << " m driven, " << r.scans << " scans, " << r.slip_events << " slip events, "
                 << r.messages << " messages";
            return SimRunResult{true, line.str()};
          },
          [&](const RotatingProfileConfig& rig) {
            const SimProfileResult r = simulateRotatingProfile(rig, options.seed, sink);
            std::ostringstream line;
            line << rig.sim.scene << " scene, " << r.sweeps << " sweeps, " << r.profiles
                 << " profiles, " << r.points << " points, " << r.duration_s << " s, " << r.messages
                 << " messages";
            return SimRunResult{true, line.str()};
          }},
      setup.rig.config);
}

ReplayRunResult replayRig(const Rig& rig, const ReplayRunOptions& options) {
  return std::visit(
      Overloaded{[&](const RotatingLidarConfig& config) {
                   ReplayOptions o;
                   o.log_path = options.log_path;
                   o.out_dir = options.out_dir;
                   o.progress = options.progress;
                   o.plots = options.plots;
                   const ReplayResult r = replayLog(o, config);
                   std::ostringstream line;
                   line << r.events << " events, " << r.sweeps << " sweeps, " << r.points
                        << " points";
                   if (r.sweeps_incomplete > 0) {
                     line << "; " << r.sweeps_incomplete << " sweeps incomplete ("
                          << r.scans_missing << " scans missing in their windows)";
                   }
                   if (r.windows_missing > 0) {
                     line << "; " << r.windows_missing
                          << " sweeps missing (their SCAN_WINDOW is not in the log)";
                   }
                   return ReplayRunResult{line.str(), r.sweeps, 0, r.points, r.log_error, r.error};
                 },
                 [&](const MobileLidarConfig& config) {
                   const MobileReplayResult r =
                       replayMobileLog(options.log_path, config, options.out_dir, options.plots);
                   std::ostringstream line;
                   line << r.events << " events, " << r.scans << " scans, " << r.points
                        << " points";
                   return ReplayRunResult{line.str(), 0, r.scans, r.points, r.log_error, r.error};
                 },
                 [&](const RotatingProfileConfig& config) {
                   const ProfileReplayResult r =
                       replayProfileLog(options.log_path, config, options.out_dir, options.plots);
                   std::ostringstream line;
                   line << r.events << " events, " << r.profiles << " profiles in " << r.sweeps
                        << " sweeps, " << r.points << " points";
                   if (r.invalid) line << ", " << r.invalid << " invalid profiles skipped";
                   return ReplayRunResult{line.str(), r.sweeps, 0, r.points, r.log_error, r.error};
                 }},
      rig.config);
}

}  // namespace sweepmap
