// `sweepmap status`: every process's health at a glance, from what they publish.
//
// StatusBoard is fed every message seen on the bus (any channel) with its receive time, and
// renders the board: one row per process, from the STATUS_<NODE> messages (process_status_t)
// of the nodes it runs (its `process` field names the process, the channel the node): its
// state (OK, DEGRADED, FAILED: the worst of its live nodes; STALE when no status of it came for
// stale_s — the processes publish one a second), the age of its last status and its detail;
// each node's state, detail and counters beneath it; per channel the message rate over the last
// rate_window_s; the mapper's progress (MAP_STATS: sweeps, voxels, memory, incomplete sweeps) and
// the rotating assembler's last sweep (SWEEP_STATUS: corrected, phi_offset, reason). It reads no
// clock: times come with the messages, so tests drive it directly.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "processes/node.hpp"

namespace sweepmap {

struct StatusBoardOptions {
  double stale_s = 3.0;        // no STATUS_* for this long: the process is marked stale
  double rate_window_s = 5.0;  // message rates over this window
};

class StatusBoard {
 public:
  explicit StatusBoard(const StatusBoardOptions& options = {});
  // A message received at `now_utime` (the receiver's clock).
  void add(const Message& msg, int64_t now_utime);
  // The board as text (a terminal table) and as JSON (one object), at `now_utime`.
  std::string text(int64_t now_utime) const;
  std::string json(int64_t now_utime) const;
  // Processes whose status is stale or whose state is FAILED (for scripts: exit status).
  int unhealthy(int64_t now_utime) const;
  // Processes seen (any status of theirs, stale or not).
  size_t processes() const { return processes_.size(); }
  // Datagrams this monitor's own receive path refused (malformed, not allowed, not signed):
  // shown beside the malformed messages.
  void setDatagramsRefused(int64_t n) { datagrams_refused_ = n; }

 private:
  struct NodeStatus {
    int64_t last_rx = 0;
    int health = 0;
    std::string detail;
    std::vector<std::pair<std::string, int64_t>> counters;
  };
  struct Process {
    std::map<std::string, NodeStatus> nodes;  // by node name (STATUS_<NODE>, lower case)
  };
  // A process's row: its state, the age of its newest status, the detail of its worst node.
  struct Row {
    std::string state;
    double age_s = 0.0;
    std::string detail;
  };
  struct Channel {
    std::deque<int64_t> rx;  // receive times within the rate window
    int64_t total = 0;
    size_t last_size = 0;
  };
  struct Map {
    int64_t sweeps = 0, points = 0, occupied = 0, free = 0, memory_bytes = 0, incomplete = 0;
    double resolution_m = 0.0;
  };
  struct Sweep {
    int64_t id = 0;
    bool corrected = false;
    double phi_offset_deg = 0.0;
    std::string reason;
  };
  bool stale(int64_t last_rx, int64_t now) const;
  std::string nodeState(const NodeStatus& n, int64_t now) const;
  Row row(const std::string& name, const Process& p, int64_t now) const;
  void addStatus(const Message& msg, int64_t now_utime);
  void processesText(std::ostream& o, int64_t now) const;
  void channelsText(std::ostream& o, int64_t now) const;
  double rateHz(const Channel& c, int64_t now) const;

  StatusBoardOptions options_;
  int64_t first_rx_ = -1;
  std::map<std::string, Process> processes_;  // by process name
  std::map<std::string, Channel> channels_;
  std::optional<Map> map_;
  std::optional<Sweep> sweep_;
  int64_t malformed_ = 0;
  int64_t datagrams_refused_ = 0;
};

struct StatusOptions {
  std::string lcm_url;
  bool once = false;      // listen for `window_s`, print once, exit
  bool json = false;      // with once: JSON instead of the table
  double window_s = 2.5;  // once: how long to listen (a 1 Hz status is seen at least twice)
  StatusBoardOptions board;
  // As the processes take them: hear only these senders, only messages signed with this key
  // (a deployment with the key on signs every status: without it, none would decode).
  std::vector<std::string> allow_senders;
  std::string key_file;
};

// Runs the dashboard (refreshing once a second until SIGINT/SIGTERM) or one snapshot. Returns
// 0 (kExitOk); with `once` 1 (kExitBadInput) when no process was seen or one is stale or
// FAILED (the message on stderr); 2 (kExitUsage) if LCM cannot start on the URL.
int runStatus(const StatusOptions& options);

}  // namespace sweepmap
