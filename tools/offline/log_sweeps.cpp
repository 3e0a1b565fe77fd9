#include "tools/offline/log_sweeps.hpp"

#include <set>

#include "calib/rotating_geometry.hpp"
#include "core/event_log.hpp"
#include "drivers/shaft_trajectory.hpp"
#include "processes/assembler_node.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/offline_bus.hpp"
#include "sweepmap/truth_rig_t.hpp"

namespace sweepmap {

LogReadResult forEachSweep(
    const std::string& log_path, const RotatingLidarConfig& rig,
    const std::function<void(const AssembledSweep&, const SweepTruth&)>& on_sweep,
    const LogSweepOptions& options) {
  EventLogReader reader(log_path);
  LogReadResult result;
  OfflineBus bus;
  AssemblerNode assembler(rig);
  bus.attach(&assembler);
  for (Node* n : options.extra_nodes) bus.attach(n);
  if (options.sink) bus.setSink(options.sink);

  ShaftTrajectory truth;
  assembler.setSweepObserver([&](const AssembledSweep& s) {
    SweepTruth t;
    if (truth.covers(s.first_ray_utime)) {
      t.phi_true_rad = wrapAngle(truth.angleAt(s.first_ray_utime));
    }
    t.alpha_true_rad = result.alpha_true_rad;
    on_sweep(s, t);
  });

  const std::set<std::string> inputs = {channels::kLidarScan, channels::kScanWindow};
  LogEvent ev;
  int64_t now = 0;
  try {
    while (reader.next(&ev)) {
      ++result.events;
      if (result.events == 1) result.first_utime = ev.utime;
      result.last_utime = ev.utime;
      now = std::max(now, ev.utime);
      if (options.progress) options.progress(reader.offset(), reader.size());
      Message m{ev.utime, ev.channel, std::move(ev.data)};
      if (m.channel == channels::kTruthShaft) {
        truth_shaft_t t;
        if (decodeMessage(m, &t)) truth.apply(fromLcm(t));
      } else if (m.channel == channels::kTruthRig) {
        truth_rig_t t;
        if (decodeMessage(m, &t)) {
          result.alpha_true_rad = t.alpha_true_rad;
          result.scene = t.scene;
        }
      } else if (inputs.count(m.channel)) {
        bus.tick(now);
        bus.deliver(m);
      } else {
        ++result.skipped_channels[m.channel];
      }
    }
  } catch (const LogError& e) {
    result.log_error = true;
    result.error = e.what();
  }
  if (!result.log_error) {
    bus.finish(now);
  } else {
    // Keep the outputs of the other nodes (e.g. save the map); no half window is assembled.
    for (Node* n : options.extra_nodes) {
      Outbox out;
      n->finish(now, out);
      for (auto& m : out.take()) {
        if (options.sink) options.sink(m);
      }
    }
  }
  result.scans = assembler.counter("scans");
  result.invalid = assembler.counter("invalid");
  result.dropped = assembler.counter("dropped");
  return result;
}

}  // namespace sweepmap
