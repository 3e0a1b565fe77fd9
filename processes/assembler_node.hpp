// sweepmap-assembler: collects the scans of each lidar window, builds the sweep
// (calib/sweep_assembly.hpp) and publishes it in chunks on SWEEP_CLOUD, then its summary
// on SWEEP_STATUS. A window is assembled once a scan at or after its end has arrived, so
// the output depends only on the messages, not on how channels interleave.
// Scans that never reach a sweep (lost on the network, dropped as out of order or invalid)
// show as gaps in the lidar's scan counter: a sweep with such a gap inside its window is
// published all the same and counted as incomplete (counters sweeps_incomplete and
// scans_missing); a gap in the motor's sweep ids (a lost SCAN_WINDOW) counts windows_missing.
#pragma once

#include <deque>
#include <functional>

#include "calib/sweep_assembly.hpp"
#include "processes/node.hpp"
#include "rigs/rotating_lidar.hpp"

namespace sweepmap {

class AssemblerNode : public Node {
 public:
  explicit AssemblerNode(const RotatingLidarConfig& rig);
  std::vector<std::string> subscriptions() const override;
  void finish(int64_t now_utime, Outbox& out) override;

  // Called with every assembled sweep (offline tools keep clouds and plate data).
  void setSweepObserver(std::function<void(const AssembledSweep&)> observer) {
    observer_ = std::move(observer);
  }
  // Called with every assembled sweep and the scans it was assembled from (calibrations that
  // place the rays again with other parameters).
  void setWindowObserver(
      std::function<void(const AssembledSweep&, const std::vector<Scan2D>&)> observer) {
    window_observer_ = std::move(observer);
  }

 protected:
  void handle(const Message& msg, Outbox& out) override;

 private:
  void onScan(const Message& msg, Outbox& out);
  void onWindow(const Message& msg, Outbox& out);
  void assembleReady(int64_t now_utime, bool flush, Outbox& out);
  void publishSweep(int64_t now_utime, const SweepWindow& window, Outbox& out);
  void noteSeqGap(const Scan2D& scan);
  int missingScansIn(const SweepWindow& window);

  // Scans missing between two accepted scans (a gap in their seq).
  struct SeqGap {
    int64_t after_utime;   // the accepted scan before the gap
    int64_t before_utime;  // the accepted scan after it
    int64_t missing;       // scans between them
  };

  RotatingLidarConfig rig_;
  std::deque<Scan2D> scans_;         // valid scans, strictly increasing utime
  std::deque<SweepWindow> windows_;  // closed windows, by start time
  int64_t last_window_end_ = INT64_MIN;
  bool has_window_id_ = false;
  int64_t last_window_id_ = 0;
  bool has_last_scan_ = false;
  int64_t last_scan_seq_ = 0, last_scan_utime_ = 0;  // the last accepted scan
  std::deque<SeqGap> gaps_;                          // by time
  // Arrival time minus stamp of the scans (see assembler_node.cpp).
  bool has_skew_ = false;
  int64_t skew_ = 0;
  int64_t candidate_skew_ = 0;
  int candidate_count_ = 0;
  std::function<void(const AssembledSweep&)> observer_;
  std::function<void(const AssembledSweep&, const std::vector<Scan2D>&)> window_observer_;
};

}  // namespace sweepmap
