#include "processes/assembler_node.hpp"

#include <algorithm>
#include <climits>
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

// The missing scans of a gap are taken as evenly spaced between its two neighbours (the
// lidar scans at a steady rate): scan i of n at after + span * i / (n + 1), i = 1..n. How
// many of them fall in [start, end), exactly, however large n is (after < before, n >= 1).
int64_t missingBetween(int64_t after, int64_t before, int64_t n, int64_t start, int64_t end) {
  using Wide = __int128;
  const Wide span = Wide(before) - after;
  // Every missing scan is stamped in (after, before): clamp the window to that span.
  const Wide from = std::clamp<Wide>(Wide(start) - after, 0, span);
  const Wide to = std::clamp<Wide>(Wide(end) - after, 0, span);
  const Wide slots = Wide(n) + 1;
  const auto ceilDiv = [](Wide a, Wide b) { return (a + b - 1) / b; };  // a >= 0, b > 0
  // after + floor(span * i / slots) >= start  <=>  i >= from * slots / span, and < end
  // <=>  i < to * slots / span.
  const Wide lo = std::max<Wide>(1, ceilDiv(from * slots, span));
  const Wide hi = std::min<Wide>(n, ceilDiv(to * slots, span) - 1);
  return hi >= lo ? static_cast<int64_t>(hi - lo + 1) : 0;
}

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
  // Any number of rays: each carries its own angle and time (a sub-range of the field of
  // view, a cluster, a model whose steps differ from the rig file's grid all assemble).
  const std::string why = validateScan(scan, 0);
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
    gaps_.clear();
    has_last_scan_ = false;
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
  noteSeqGap(scan);
  scans_.push_back(std::move(scan));
  while (scans_.size() > static_cast<size_t>(std::max(1, rig_.assembler.max_pending_scans))) {
    scans_.pop_front();
    count("scans_evicted");
    // Gaps before the oldest pending scan are of evicted scans (counted above): forget them,
    // so a lidar without a motor keeps no growing list.
    while (!gaps_.empty() && gaps_.front().before_utime <= scans_.front().utime) {
      gaps_.pop_front();
    }
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
  // Sweep ids count up from 0 in one motor process; a smaller one is a restarted motor.
  if (has_window_id_ && m.sweep_id > last_window_id_) {
    const uint64_t skipped =
        static_cast<uint64_t>(m.sweep_id) - static_cast<uint64_t>(last_window_id_) - 1;
    if (skipped > 0) {
      count("windows_missing", static_cast<int64_t>(std::min<uint64_t>(skipped, INT64_MAX)));
      reportEvent("no SCAN_WINDOW for sweeps " + std::to_string(last_window_id_ + 1) + ".." +
                  std::to_string(m.sweep_id - 1) + " (lost on the way): those sweeps are missing");
    }
  }
  has_window_id_ = true;
  last_window_id_ = m.sweep_id;
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
  AssembledSweep sweep = assembleSweep(in_window, window, rig_);
  sweep.missing_scans = missingScansIn(window);
  if (sweep.missing_scans > 0) {
    count("sweeps_incomplete");
    count("scans_missing", sweep.missing_scans);
    reportEvent("sweep " + std::to_string(window.sweep_id) +
                " incomplete: " + std::to_string(sweep.missing_scans) + " of " +
                std::to_string(sweep.missing_scans + sweep.scans) +
                " scans missing (lost on the way, or dropped here as out of order or invalid)");
    // The plate may be among what was lost: one scan lost over it in mode 1 moves phi by ~1 deg.
    uncorrectSweep(
        std::to_string(sweep.missing_scans) + " scans missing: the plate may be incompletely seen",
        &sweep);
  }
  const auto chunks = toChunks(sweep, rig_.assembler.chunk_points);
  for (const auto& c : chunks) out.publish(channels::kSweepCloud, now_utime, c);
  out.publish(channels::kSweepStatus, now_utime, toStatus(sweep, static_cast<int>(chunks.size())));
  count("sweeps");
  if (!sweep.corrected) count("sweeps_uncorrected");
  if (window_observer_) window_observer_(sweep, in_window);
  if (observer_) observer_(sweep);
}

void AssemblerNode::noteSeqGap(const Scan2D& scan) {
  // A seq that goes back is a restarted lidar process: no gap. At most one scan per microsecond
  // between the two: a wild seq cannot overflow the count.
  if (has_last_scan_ && scan.seq > last_scan_seq_ &&
      static_cast<uint64_t>(scan.seq) - static_cast<uint64_t>(last_scan_seq_) > 1) {
    const uint64_t missing = std::min<uint64_t>(
        static_cast<uint64_t>(scan.seq) - static_cast<uint64_t>(last_scan_seq_) - 1,
        static_cast<uint64_t>(scan.utime) - static_cast<uint64_t>(last_scan_utime_));
    gaps_.push_back({last_scan_utime_, scan.utime, static_cast<int64_t>(missing)});
  }
  has_last_scan_ = true;
  last_scan_seq_ = scan.seq;
  last_scan_utime_ = scan.utime;
}

int AssemblerNode::missingScansIn(const SweepWindow& window) {
  int64_t missing = 0;
  for (const SeqGap& g : gaps_) {
    if (g.after_utime >= window.end_utime) break;
    missing += missingBetween(g.after_utime, g.before_utime, g.missing, window.start_utime,
                              window.end_utime);
  }
  // Gaps wholly before this window's end can touch no later window.
  while (!gaps_.empty() && gaps_.front().before_utime <= window.end_utime) gaps_.pop_front();
  return static_cast<int>(std::min<int64_t>(missing, INT32_MAX));
}

void AssemblerNode::finish(int64_t now_utime, Outbox& out) { assembleReady(now_utime, true, out); }

}  // namespace sweepmap
