// The one loop that plays an LCM log offline: every event in log order, the chosen input
// channels delivered to the process classes on an OfflineBus (the bus's clock moved to the
// event's time first), other channels handed to handlers (ground truth, raw scans kept
// aside) or counted as skipped. Replay, calibration and evaluation all read logs through
// it, so they see exactly what the live processes would. Corrupt regions and a truncated
// tail are skipped as LCM's own reader skips them (to the next good event header): every
// event outside them is delivered, and the skipped byte ranges are reported.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>

#include "core/event_log.hpp"
#include "processes/node.hpp"
#include "processes/offline_bus.hpp"

namespace sweepmap {

struct LogPlayResult {
  int64_t events = 0;       // every event read, whatever its channel
  int64_t first_utime = 0;  // of the first and last event read
  int64_t last_utime = 0;
  int64_t now_utime = 0;  // the bus's clock at the end: the latest event time
  std::map<std::string, int64_t> skipped_channels;  // neither input nor handled
  bool log_error = false;  // the log had corrupt or truncated bytes (skipped)
  std::string error;       // "PATH: byte B to E skipped: why; ..."
  std::vector<SkippedRange> skipped_ranges;
};

class LogPlayer {
 public:
  using Handler = std::function<void(const Message&)>;

  // Opens the log; throws LogError if it cannot be opened.
  explicit LogPlayer(const std::string& path);
  ~LogPlayer();

  OfflineBus& bus() { return bus_; }
  // Channels delivered to the bus's nodes, each after bus().tick(event time).
  void addInputs(const std::set<std::string>& channels);
  // A channel consumed here instead (no tick): the handler sees each of its messages.
  void handle(const std::string& channel, Handler handler);
  void setProgress(std::function<void(uint64_t offset, uint64_t size)> progress);

  // Plays the whole log, skipping what is corrupt. Does not finish the bus: the caller
  // decides what a damaged log means for pending work (finish()).
  LogPlayResult play();
  // bus().finish() at the last event time.
  void finish();

 private:
  std::unique_ptr<EventLogReader> reader_;
  OfflineBus bus_;
  std::set<std::string> inputs_;
  std::map<std::string, Handler> handlers_;
  std::function<void(uint64_t, uint64_t)> progress_;
  int64_t now_ = 0;
};

}  // namespace sweepmap
