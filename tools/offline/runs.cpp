#include "tools/offline/runs.hpp"

#include <algorithm>
#include <memory>
#include <sstream>
#include <type_traits>

#include "core/event_log.hpp"
#include "core/progress.hpp"
#include "processes/channels.hpp"
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
  s.scene_path = resolveSceneFile(scene.empty() ? defaultSceneName(s.rig.kind()) : scene);
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

namespace {

// The fraction of a simulation done, from the messages it has sent: rotating_lidar by its
// SCAN_WINDOWs (one per sweep), mobile_lidar by simulated time; rig C's is not known (-1).
std::function<double(const Message&)> simFraction(const SimSetup& setup, int sweeps) {
  auto first = std::make_shared<int64_t>(-1);
  auto windows = std::make_shared<int64_t>(0);
  if (std::holds_alternative<RotatingLidarConfig>(setup.rig.config)) {
    return [windows, sweeps](const Message& m) {
      if (m.channel == channels::kScanWindow) ++*windows;
      return static_cast<double>(*windows) / std::max(1, sweeps);
    };
  }
  if (const auto* mobile = std::get_if<MobileLidarConfig>(&setup.rig.config)) {
    const double duration_us = mobile->sim.duration_s * 1e6;
    return [first, duration_us](const Message& m) {
      if (*first < 0) *first = m.utime;
      return duration_us > 0 ? static_cast<double>(m.utime - *first) / duration_us : -1.0;
    };
  }
  return [](const Message&) { return -1.0; };
}

}  // namespace

SimRunResult simulateRig(const SimSetup& setup, const SimRunOptions& options,
                         const std::function<void(const Message&)>& output) {
  ProgressOptions po;
  po.enabled = options.progress;
  Progress bar("sim", po);
  const auto fraction = simFraction(setup, options.sweeps);
  const auto sink = [&](const Message& m) {
    output(m);
    if (options.progress) bar.update(fraction(m));
  };
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

namespace {

ReplayRunResult replayOfKind(const Rig& rig, const ReplayRunOptions& options) {
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
                   const MobileReplayResult r = replayMobileLog(
                       options.log_path, config, options.out_dir, options.plots, options.progress);
                   std::ostringstream line;
                   line << r.events << " events, " << r.scans << " scans, " << r.points
                        << " points";
                   return ReplayRunResult{line.str(), 0, r.scans, r.points, r.log_error, r.error};
                 },
                 [&](const RotatingProfileConfig& config) {
                   const ProfileReplayResult r = replayProfileLog(
                       options.log_path, config, options.out_dir, options.plots, options.progress);
                   std::ostringstream line;
                   line << r.events << " events, " << r.profiles << " profiles in " << r.sweeps
                        << " sweeps, " << r.points << " points";
                   if (r.invalid) line << ", " << r.invalid << " invalid profiles skipped";
                   return ReplayRunResult{line.str(), r.sweeps, 0, r.points, r.log_error, r.error};
                 }},
      rig.config);
}

}  // namespace

ReplayRunResult replayRig(const Rig& rig, const ReplayRunOptions& options) {
  ReplayRunResult r = replayOfKind(rig, options);
  r.nothing = rig.kind() == RigKind::kMobileLidar ? r.scans == 0 : r.sweeps == 0;
  if (r.nothing && !r.log_error) r.error = explainEmptyReplay(rig, options.log_path);
  return r;
}

std::map<std::string, int64_t> logChannelCounts(const std::string& log_path) {
  std::map<std::string, int64_t> counts;
  EventLogReader reader(log_path);
  reader.setResync(true);
  LogEvent e;
  try {
    while (reader.next(&e)) ++counts[e.channel];
  } catch (const LogError&) {
    // a corrupt tail: the counts up to it
  }
  return counts;
}

std::string explainEmptyReplay(const Rig& rig, const std::string& log_path) {
  struct Need {
    RigKind kind;
    std::vector<std::string> channels;  // the raw channels its replay needs
  };
  const std::vector<Need> needs = {
      {RigKind::kRotatingLidar, {channels::kScanWindow, channels::kLidarScan}},
      {RigKind::kMobileLidar, {channels::kLidarScan, channels::kWheelTicks, channels::kImu}},
      {RigKind::kRotatingProfile, {channels::kProfile}}};
  const std::map<std::string, int64_t> counts = logChannelCounts(log_path);
  std::ostringstream why;
  why << "nothing made: a " << rig.kindName() << " rig (" << rig.path << ") needs ";
  for (const Need& n : needs) {
    if (n.kind != rig.kind()) continue;
    for (size_t i = 0; i < n.channels.size(); ++i) why << (i ? " + " : "") << n.channels[i];
  }
  if (rig.kind() != RigKind::kRotatingProfile && rig.lidar().beam_count > 0) {
    why << " (" << rig.lidar().beam_count << " ranges per LIDAR_SCAN)";
  }
  if (counts.empty()) {
    why << "; the log " << log_path << " holds no event";
    return why.str();
  }
  why << "; the log " << log_path << " holds";
  for (const auto& [channel, n] : counts) why << " " << channel << " x" << n;
  // The kind whose first (distinguishing) channel the log has.
  for (const Need& n : needs) {
    if (n.kind != rig.kind() &&
        counts.count(n.channels.front() == channels::kLidarScan ? n.channels[1]
                                                                : n.channels.front())) {
      why << ": a log of a " << rigKindName(n.kind) << " rig? (--rig " << defaultRigName(n.kind)
          << ")";
      break;
    }
  }
  return why.str();
}

}  // namespace sweepmap
