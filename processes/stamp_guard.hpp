// Time that cannot be poisoned. Every message carries its own stamp (`utime`, the first field
// of every sweepmap type); a node compares it with its own clock (the message's arrival) and
// with the stream it belongs to. Per channel, the offset stamp - arrival of a healthy stream
// is nearly constant (a latency, or the fixed shift of a log played by lcm-logplayer); a
// message whose offset leaves the stream's by more than the channel's tolerance is refused
// (counted, with the offset in the status detail), so no single message stamped a day ahead
// can move an estimate or freeze a channel. A real jump (a clock stepped by NTP, a log played
// again) is accepted once `confirmations` messages in a row agree on the new offset; the ones
// before are refused. A stream's first message is judged against the node's other streams
// of its kind (they share the host clock, or the one shift of a played log), so a message
// stamped a day ahead cannot anchor a new stream either; only a node's very first message
// has nothing to be judged against.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace sweepmap {

class StampGuard {
 public:
  struct Policy {
    int64_t tolerance_us;
    int confirmations;
  };
  // The channels that are time series: the sensors' raw streams and what is derived from
  // them. Others (MAP_SAVE, STATUS_*, TRUTH_*) are not checked.
  static std::optional<Policy> policyFor(const std::string& channel);

  // Whether a message of `channel` stamped `stamp_us` that arrived at `arrival_us` may reach
  // the node; `why` says why not.
  bool admit(const std::string& channel, int64_t stamp_us, int64_t arrival_us, std::string* why);

 private:
  struct Stream {
    int64_t tolerance_us = 0;  // its policy's: streams of one kind share an offset
    int64_t offset_us = 0;     // of the last message admitted
    int pending = 0;           // messages in a row at another offset
    int64_t pending_offset_us = 0;
  };
  // The offset of an admitted stream of the same kind as `channel` (the first in name
  // order: deterministic), if there is one.
  std::optional<int64_t> peerOffset(const std::string& channel, int64_t tolerance_us) const;

  std::map<std::string, Stream> streams_;
};

}  // namespace sweepmap
