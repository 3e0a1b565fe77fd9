#include "processes/assembler_node.hpp"

#include <algorithm>
#include <cstdlib>

#include "processes/channels.hpp"
#include "processes/convert.hpp"

namespace sweepmap {
namespace {

// The difference between a scan's stamp and when it arrived (or was logged) is steady for
// one source, whatever the clocks (lcm-logplayer plays old logs "now"). A scan whose
// difference moves by more than this is not trusted -- one far-future stamp would
// otherwise make every later scan look out of order -- unless a few in a row agree on
// the new difference: then the source's clock really stepped and assembly starts over.
constexpr int64_t kMaxClockSkewUs = 10LL * 1000000;
constexpr int kScansToAcceptClockStep = 3;

}  // namespace

AssemblerNode::AssemblerNode(const RotatingLidarConfig& rig) : Node("assembler"), rig_(rig) {}

std::vector<std::string> AssemblerNode::subscriptions() const {
  return {channels::kLidarScan, channels::kScanWindow};
}

void AssemblerNode::handle(const Message& msg, Outbox& out) {
  if (msg.channel == channels::kLidarScan) {
    onScan(msg, out);
  } else if (msg.channel == channels::kScanWindow) {
    onWindow(msg, out);
  }
}

void AssemblerNode::onScan(const Message& msg, Outbox& out) {
  lidar_scan_t m;
  if (!decodeMessage(msg, &m)) {
    reportError("invalid", "malformed lidar_scan_t on " + msg.channel);
    return;
  }
  Scan2D scan = fromLcm(m);
  const std::string why = validateScan(scan, rig_.lidar.beam_count);
  if (!why.empty()) {
    reportError("invalid", "scan " + std::to_string(scan.seq) + " dropped: " + why);
    return;
  }
  const int64_t skew = msg.utime - scan.utime;
  if (has_skew_ && std::llabs(skew - skew_) > kMaxClockSkewUs) {
    if (std::llabs(skew - candidate_skew_) <= kMaxClockSkewUs) {
      ++candidate_count_;
    } else {
      candidate_skew_ = skew;
      candidate_count_ = 1;
    }
    if (candidate_count_ < kScansToAcceptClockStep) {
      reportError("invalid", "scan " + std::to_string(scan.seq) + " stamped " +
                                 std::to_string(skew_ - skew) + " us off its stream, dropped");
      return;
    }
    reportError("clock_resets", "the scan clock stepped by " + std::to_string(skew_ - skew) +
                                    " us: pending scans and windows discarded");
    scans_.clear();
    windows_.clear();
    last_window_end_ = INT64_MIN;
  }
  has_skew_ = true;
  skew_ = skew;
  candidate_count_ = 0;
  if (!scans_.empty() && scan.utime <= scans_.back().utime) {
    reportError("dropped", "scan " + std::to_string(scan.seq) + " out of order, dropped");
    return;
  }
  count("scans");
  scans_.push_back(std::move(scan));
  while (scans_.size() > static_cast<size_t>(std::max(1, rig_.assembler.max_pending_scans))) {
    scans_.pop_front();
    count("scans_evicted");
  }
  assembleReady(msg.utime, false, out);
}

void AssemblerNode::onWindow(const Message& msg, Outbox& out) {
  scan_window_t m;
  if (!decodeMessage(msg, &m)) {
    reportError("invalid", "malformed scan_window_t on " + msg.channel);
    return;
  }
  const std::string why = validateWindow(m);
  if (!why.empty()) {
    reportError("invalid", "window of sweep " + std::to_string(m.sweep_id) + " dropped: " + why);
    return;
  }
  if (has_skew_ && std::llabs((msg.utime - m.end_utime) - skew_) > kMaxClockSkewUs) {
    reportError("invalid", "window of sweep " + std::to_string(m.sweep_id) +
                               " does not end near the scans' time, dropped");
    return;
  }
  if (m.start_utime < last_window_end_) {
    reportError("dropped", "window of sweep " + std::to_string(m.sweep_id) +
                               " overlaps the previous one, dropped");
    return;
  }
  last_window_end_ = m.end_utime;
  count("windows");
  windows_.push_back(fromLcm(m));
  assembleReady(msg.utime, false, out);
}

void AssemblerNode::assembleReady(int64_t now_utime, bool flush, Outbox& out) {
  while (!windows_.empty()) {
    const SweepWindow& w = windows_.front();
    const bool complete = !scans_.empty() && scans_.back().utime >= w.end_utime;
    if (!complete && !flush) return;
    const SweepWindow window = w;
    windows_.pop_front();
    publishSweep(now_utime, window, out);
  }
}

void AssemblerNode::publishSweep(int64_t now_utime, const SweepWindow& window, Outbox& out) {
  // Scans before the window are of no sweep; scans in it are consumed.
  std::vector<Scan2D> in_window;
  while (!scans_.empty() && scans_.front().utime < window.end_utime) {
    if (scans_.front().utime >= window.start_utime) {
      in_window.push_back(std::move(scans_.front()));
    }
    scans_.pop_front();
  }
  const AssembledSweep sweep = assembleSweep(in_window, window, rig_);
  const auto chunks = toChunks(sweep, rig_.assembler.chunk_points);
  for (const auto& c : chunks) out.publish(channels::kSweepCloud, now_utime, c);
  out.publish(channels::kSweepStatus, now_utime, toStatus(sweep, static_cast<int>(chunks.size())));
  count("sweeps");
  if (!sweep.corrected) count("sweeps_uncorrected");
  if (window_observer_) window_observer_(sweep, in_window);
  if (observer_) observer_(sweep);
}

void AssemblerNode::finish(int64_t now_utime, Outbox& out) { assembleReady(now_utime, true, out); }

}  // namespace sweepmap
