#include "tools/offline/log_sweeps.hpp"

#include "calib/rotating_geometry.hpp"
#include "devices/shaft_trajectory.hpp"
#include "processes/assembler_node.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "sweepmap/truth_rig_errors_t.hpp"
#include "sweepmap/truth_rig_t.hpp"
#include "tools/offline/log_player.hpp"

namespace sweepmap {

LogReadResult forEachSweep(
    const std::string& log_path, const RotatingLidarConfig& rig,
    const std::function<void(const AssembledSweep&, const SweepTruth&)>& on_sweep,
    const LogSweepOptions& options) {
  LogPlayer player(log_path);
  LogReadResult result;
  AssemblerNode assembler(rig);
  player.bus().attach(&assembler);
  for (Node* n : options.extra_nodes) player.bus().attach(n);
  if (options.sink) player.bus().setSink(options.sink);
  player.addInputs({channels::kLidarScan, channels::kScanWindow});
  if (options.progress) player.setProgress(options.progress);

  ShaftTrajectory truth;
  player.handle(channels::kTruthShaft, [&](const Message& m) {
    truth_shaft_t t;
    if (decodeMessage(m, &t)) truth.apply(fromLcm(t));
  });
  player.handle(channels::kTruthRig, [&](const Message& m) {
    truth_rig_t t;
    if (decodeMessage(m, &t)) {
      result.alpha_true_rad = t.alpha_true_rad;
      result.lidar_offset_x_true_m = t.lidar_offset_x_m;
      result.scene = t.scene;
    }
  });
  player.handle(channels::kTruthRigErrors, [&](const Message& m) {
    truth_rig_errors_t t;
    if (decodeMessage(m, &t)) {
      result.scan_plane_tilt_true_rad = t.scan_plane_tilt_rad;
      result.mirror_offset_true_rad = t.mirror_offset_rad;
      result.plate_thickness_true_m = t.plate_thickness_m;
    }
  });
  if (options.on_window_scans) assembler.setWindowObserver(options.on_window_scans);
  assembler.setSweepObserver([&](const AssembledSweep& s) {
    SweepTruth t;
    if (truth.covers(s.first_ray_utime)) {
      t.phi_true_rad = wrapAngle(truth.angleAt(s.first_ray_utime));
    }
    t.alpha_true_rad = result.alpha_true_rad;
    on_sweep(s, t);
  });

  const LogPlayResult played = player.play();
  result.events = played.events;
  result.first_utime = played.first_utime;
  result.last_utime = played.last_utime;
  result.skipped_channels = played.skipped_channels;
  result.log_error = played.log_error;
  result.error = played.error;
  if (!result.log_error) {
    player.finish();
  } else {
    // Keep the outputs of the other nodes (e.g. save the map); no half window is assembled.
    for (Node* n : options.extra_nodes) {
      Outbox out;
      n->finish(played.now_utime, out);
      for (auto& m : out.take()) {
        if (options.sink) options.sink(m);
      }
    }
  }
  result.scans = assembler.counter("scans");
  result.invalid = assembler.counter("invalid");
  result.dropped = assembler.counter("dropped");
  result.sweeps_incomplete = assembler.counter("sweeps_incomplete");
  result.scans_missing = assembler.counter("scans_missing");
  result.windows_missing = assembler.counter("windows_missing");
  return result;
}

}  // namespace sweepmap
