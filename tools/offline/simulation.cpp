#include "tools/offline/simulation.hpp"

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/lidar_node.hpp"
#include "processes/motor_controller.hpp"
#include "processes/offline_bus.hpp"
#include "processes/sim_setup.hpp"
#include "processes/truth_sweep_node.hpp"
#include "sim/lidar.hpp"
#include "sim/stepper.hpp"

namespace sweepmap {

void splitSimOverrides(const std::vector<std::string>& overrides,
                       std::vector<std::string>* rig_sets, std::vector<std::string>* scene_sets) {
  for (const auto& o : overrides) {
    if (o.rfind("scene.", 0) == 0) {
      scene_sets->push_back(o.substr(6));
    } else {
      rig_sets->push_back(o);
    }
  }
}

SimResult simulate(const SimOptions& options, const std::function<void(const Message&)>& sink) {
  const RotatingLidarConfig& rig = options.rig;
  const Scene scene(options.scene, rig.plate);
  const int64_t t0 = kSimEpochUtime;
  SimResult result;

  OfflineBus bus;
  int64_t now = t0;
  bus.setSink([&](const Message& m) {
    ++result.messages;
    sink(m);
  });
  std::vector<ShaftSegment> truth_pending;
  SimStepper stepper(rig.motor, rig.sim, stepperSeed(options.seed), kSimInitialShaftAngleRad, t0,
                     [&](const ShaftSegment& s) { truth_pending.push_back(s); });
  SimLidar lidar(rig.lidar, rig.sim, rig.plate, scene, &stepper.trajectory(),
                 lidarSeed(options.seed), t0);
  MotorController motor(rig, &stepper, options.sweeps, t0);
  LidarNode lidar_node(rig.lidar, &lidar);
  TruthSweepNode truth_sweep(&stepper.trajectory(), rig.sim.alpha_true_deg * M_PI / 180.0);
  bus.attach(&motor);
  bus.attach(&lidar_node);
  bus.attach(&truth_sweep);

  const auto flushTruth = [&] {
    for (const auto& s : truth_pending) {
      Outbox out;
      out.publish(channels::kTruthShaft, now, toLcm(s, now));
      for (auto& m : out.take()) bus.publish(m);
    }
    truth_pending.clear();
  };
  const auto publishTruthRig = [&] {
    Outbox out;
    out.publish(channels::kTruthRig, now, makeTruthRig(rig, options.scene, scene, now));
    out.publish(channels::kTruthRigErrors, now, makeTruthRigErrors(rig.sim, now));
    for (auto& m : out.take()) bus.publish(m);
  };

  flushTruth();
  publishTruthRig();
  // Enough for the sweeps with generous slack; a stuck controller ends the run.
  const ScanMode mode = scanMode(rig.motor.mode);
  const int64_t limit_us =
      static_cast<int64_t>((60.0 + 3.0 * mode.period_s) * 1e6) * std::max(1, options.sweeps);
  const int64_t drain_us = static_cast<int64_t>((rig.sim.lidar_latency_ms + 100.0) * 1000.0);
  int64_t done_at = -1;
  int64_t next_truth_rig = t0 + 1000000;
  for (now = t0; now - t0 <= limit_us; now += options.tick_us) {
    bus.tick(now);
    flushTruth();
    if (now >= next_truth_rig) {
      publishTruthRig();
      next_truth_rig += 1000000;
    }
    if (motor.done() && done_at < 0) done_at = now;
    if (done_at >= 0 && now - done_at >= drain_us) break;
  }
  bus.finish(now);
  result.sweeps_done = motor.sweepsDone();
  result.simulated_us = now - t0;
  result.motor_fault = motor.phase() == MotorController::Phase::kFault;
  return result;
}

}  // namespace sweepmap
