#include "processes/truth_sweep_node.hpp"

#include "calib/rotating_geometry.hpp"
#include "processes/channels.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "sweepmap/truth_sweep_t.hpp"

namespace sweepmap {

TruthSweepNode::TruthSweepNode(const ShaftTrajectory* truth, double alpha_true_rad)
    : Node("truth_sweep"), truth_(truth), alpha_true_rad_(alpha_true_rad) {}

std::vector<std::string> TruthSweepNode::subscriptions() const {
  return {channels::kLidarScan, channels::kScanWindow};
}

void TruthSweepNode::handle(const Message& msg, Outbox& out) {
  if (msg.channel == channels::kLidarScan) {
    lidar_scan_t s;
    if (!decodeMessage(msg, &s)) return;
    scan_utimes_.push_back(s.utime);
    while (scan_utimes_.size() > 4000) scan_utimes_.pop_front();
  } else {
    scan_window_t w;
    if (!decodeMessage(msg, &w)) return;
    windows_.push_back({w.sweep_id, w.start_utime, w.end_utime});
  }
  publishReady(msg.utime, out);
}

void TruthSweepNode::publishReady(int64_t now, Outbox& out) {
  while (!windows_.empty()) {
    const Window w = windows_.front();
    int64_t first = -1;
    for (const int64_t t : scan_utimes_) {
      if (t >= w.start && t < w.end) {
        first = t;
        break;
      }
    }
    if (first < 0) {
      // No scan of the window yet: wait while later scans may still come.
      if (scan_utimes_.empty() || scan_utimes_.back() < w.end) return;
      windows_.pop_front();  // the window had no scans at all
      continue;
    }
    windows_.pop_front();
    if (!truth_->covers(first)) continue;
    truth_sweep_t m;
    m.utime = now;
    m.sweep_id = w.sweep_id;
    m.first_ray_utime = first;
    m.phi_offset_true_rad = wrapAngle(truth_->angleAt(first));
    m.alpha_true_rad = alpha_true_rad_;
    out.publish(channels::kTruthSweep, now, m);
  }
}

}  // namespace sweepmap
