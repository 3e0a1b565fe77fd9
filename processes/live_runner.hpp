// Runs nodes live over LCM. The LCM receive callback only copies the message into a
// bounded queue (drops are counted); a worker thread hands messages to the nodes, ticks
// them every `tick_period_ms` of wall-clock time and publishes what they return.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "net/lcm_datagram.hpp"
#include "processes/node.hpp"

namespace lcm {
class LCM;
}
namespace sweepmap::net {
class MessageAuth;
}

namespace sweepmap {

struct LiveOptions {
  // The URL is required: a caller that forgot it must not be routed silently through liblcm's
  // receive code (as a default of "memq://" would do for an udpm:// handle).
  explicit LiveOptions(std::string url) : lcm_url(std::move(url)) {}
  // The provider URL the LCM handle was made with. An udpm:// URL (or "" under
  // LCM_DEFAULT_URL=udpm://...) is received by sweepmap's own validating receiver
  // (net/udpm_receiver.hpp), never by liblcm 1.3.1's, which one malformed datagram crashes;
  // liblcm then only publishes. Other providers (memq://, file://) are in-process: liblcm
  // receives them. Processes set it from --lcm-url (liveOptions in cli_common.hpp).
  std::string lcm_url;
  // Receive only from these IPv4 senders (host byte order); empty: any (udpm:// only).
  std::set<uint32_t> allowed_senders;
  // Set: every message published is signed with this key, and only messages signed with it
  // are received (net/message_auth.hpp; udpm:// only).
  std::shared_ptr<const net::MessageAuth> auth;
  int tick_period_ms = 1;
  // true: a receiver thread wakes the worker for every message. false: no receiver thread;
  // the worker takes the messages LCM has buffered at each tick (they wait at most
  // tick_period_ms), so a stream of small messages costs one wake-up of ours per tick
  // instead of two thread switches per message (which dominate the cost of a cheap node
  // such as the odometry's). Results do not change: nodes never read the wall clock for them.
  bool wake_on_message = true;
  size_t queue_capacity = 10000;            // messages (the rig's network.queue_messages)
  size_t queue_capacity_bytes = 64u << 20;  // and bytes (network.queue_mb; a Pi has little memory)
  // The bounds of the datagram receive path (udpm:// only; the rig's network.* keys).
  net::ReassemblyLimits reassembly;
  // Polled after every tick: return true to stop (e.g. the motor has done its sweeps).
  std::function<bool()> should_stop;
  // Polled before each sd_notify WATCHDOG=1 (under systemd or `sweepmap launch`): false
  // withholds the ping, so that a process whose device thread is stuck is restarted too.
  std::function<bool()> healthy;
  // The process named in the nodes' status messages; "" = this executable's name without
  // its "sweepmap-" prefix (sweepmap-lidar: "lidar").
  std::string process;
};

// Wall-clock time [us] (LCM's utime convention), read once and then advanced monotonically.
int64_t wallUtime();
// wallUtime() * 1000 - CLOCK_MONOTONIC [ns], constant for the process: converts a kernel
// timestamp (CLOCK_MONOTONIC) to utime and a utime to a monotonic deadline.
int64_t wallMinusMonotonicNs();

// Installs SIGINT/SIGTERM/SIGHUP handlers that make runLive return after finish().
void installStopSignals();
bool stopRequested();

// Returns 0 after a clean stop (signal or should_stop), non-zero if LCM failed.
int runLive(lcm::LCM& lcm, const std::vector<Node*>& nodes, const LiveOptions& options);

// Publishes already encoded messages, signed when `auth` is given.
void publishAll(lcm::LCM& lcm, const std::vector<Message>& messages,
                const net::MessageAuth* auth = nullptr);

}  // namespace sweepmap
