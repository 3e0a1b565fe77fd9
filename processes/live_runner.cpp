#include "processes/live_runner.hpp"

#include <cerrno>
#include <chrono>
#include <csignal>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "core/exit_codes.hpp"
#include "net/udpm_receiver.hpp"
#include "processes/inbox.hpp"
#include "processes/sd_notify.hpp"

namespace sweepmap {
namespace {

std::atomic<bool> g_stop{false};

void onSignal(int) { g_stop = true; }

// This executable's name without the "sweepmap-" prefix (glibc's short invocation name).
std::string thisProcessName() {
  const std::string name = program_invocation_short_name;
  const std::string prefix = "sweepmap-";
  return name.rfind(prefix, 0) == 0 ? name.substr(prefix.size()) : name;
}

// LCM's receive callback: copies the message into the inbox. Subscribed with
// subscribeFunction (a plain function and a context pointer), not with subscribe(channel,
// &Class::method, object): GCC 12's -fsanitize=vptr miscompiles the wrapper's call through a
// pointer to member (lcm-cpp-impl.hpp:108, `(subs->handler->*subs->handlerMethod)(...)`
// reads a wrong `subs` and crashes; clang's is fine), so a sanitizer build could not run.
class RawHandler {
 public:
  RawHandler(Inbox* inbox, bool wake) : inbox_(inbox), wake_(wake) {}
  static void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                        RawHandler* self) {
    Message m;
    m.utime = wallUtime();
    m.channel = channel;
    const auto* p = static_cast<const uint8_t*>(rbuf->data);
    m.data.assign(p, p + rbuf->data_size);
    self->inbox_->push(std::move(m), self->wake_);
  }
  void onDatagramMessage(const std::string& channel, const uint8_t* data, size_t size) {
    Message m;
    m.utime = wallUtime();
    m.channel = channel;
    m.data.assign(data, data + size);
    inbox_->push(std::move(m), wake_);
  }

 private:
  Inbox* inbox_;
  bool wake_;
};

// One runLive: the nodes' subscriptions, the optional receiver thread and the worker's loop.
// The subscriptions end with it (the handler they point to lives here).
class LiveRun {
 public:
  LiveRun(lcm::LCM& lcm, const std::vector<Node*>& nodes, const LiveOptions& options)
      : lcm_(lcm),
        nodes_(nodes),
        options_(options),
        inbox_(options.queue_capacity, options.queue_capacity_bytes),
        handler_(&inbox_, options.wake_on_message) {
    if (net::isUdpmUrl(options.lcm_url)) {
      net::ReceiverOptions receive;
      receive.allowed_senders = options.allowed_senders;
      receive.limits = options.reassembly;
      if (options.auth) receive.auth = *options.auth;
      udpm_ = std::make_unique<net::UdpmReceiver>(options.lcm_url, std::move(receive));
    }
  }

  void subscribe() {
    for (Node* n : nodes_) {
      for (const auto& ch : n->subscriptions()) {
        if (subscribers_[ch].empty() && udpm_) {
          udpm_->subscribe(ch, [this](const std::string& c, const uint8_t* d, size_t n) {
            handler_.onDatagramMessage(c, d, n);
          });
        } else if (subscribers_[ch].empty()) {
          subscriptions_.push_back(lcm_.subscribeFunction(ch, &RawHandler::onMessage, &handler_));
        }
        subscribers_[ch].push_back(n);
      }
    }
  }

  // Waking per message: a receiver thread hands each message over at once. Otherwise the
  // worker itself takes what LCM has buffered at each tick, so a message costs no thread
  // switch of ours (LCM's own receive thread still wakes for it).
  void startReceiver() {
    if (!options_.wake_on_message) return;
    receiver_ = std::thread([this] {
      while (receiving_) {
        if (failed(handleTimeout(50))) {
          lcm_failed_ = true;
          break;
        }
      }
    });
  }

  // Until a signal, options.should_stop or an LCM failure. Tells the supervisor (systemd or
  // `sweepmap launch`) READY=1 as it starts and WATCHDOG=1 from this loop only: a worker
  // stuck in a node stops the pings and is restarted.
  void loop() {
    const auto period = std::chrono::milliseconds(std::max(1, options_.tick_period_ms));
    auto next_tick = std::chrono::steady_clock::now();
    notifier_.ready();
    while (!g_stop && !lcm_failed_) {
      if (!options_.healthy || options_.healthy()) notifier_.alive();
      receiveBuffered();
      for (const Message& m : inbox_.popUntil(next_tick)) dispatch(m);
      if (std::chrono::steady_clock::now() < next_tick) continue;
      tickNodes();
      next_tick += period;
      if (std::chrono::steady_clock::now() > next_tick + 100 * period) {
        next_tick = std::chrono::steady_clock::now();  // fell behind: do not burst
      }
      countDropped();
      if (options_.should_stop && options_.should_stop()) break;
    }
  }

  // Drains what arrived before the stop, lets the nodes flush, stops the receiver and
  // unsubscribes. Returns false if LCM failed.
  bool finish() {
    notifier_.stopping();
    auto drain_until = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
    if (!options_.wake_on_message) {
      while (!lcm_failed_ && std::chrono::steady_clock::now() < drain_until) {
        if (failed(handleTimeout(20))) lcm_failed_ = true;
      }
      drain_until = std::chrono::steady_clock::now();
    }
    for (const Message& m : inbox_.popUntil(drain_until)) dispatch(m);
    countDropped(true);
    reportTransportCounters();
    const int64_t now = wallUtime();
    for (Node* n : nodes_) {
      Outbox out;
      n->finish(now, out);
      n->publishStatus(now, out);
      publishAll(lcm_, out.take(), options_.auth.get());
    }
    receiving_ = false;
    if (receiver_.joinable()) receiver_.join();
    for (lcm::Subscription* s : subscriptions_) lcm_.unsubscribe(s);
    return !lcm_failed_;
  }

 private:
  // A handle call that failed, not one that a signal interrupted (select's EINTR: the stop
  // signal arriving while this thread waits is no failure of LCM).
  static bool failed(int rc) { return rc < 0 && errno != EINTR; }

  // One wait for traffic on whichever receive path this run has; the receive path's counters
  // are copied for the worker (the receiver thread may be the caller).
  int handleTimeout(int ms) {
    if (!udpm_) return lcm_.handleTimeout(ms);
    const int rc = udpm_->handleTimeout(ms);
    std::lock_guard<std::mutex> lock(net_mutex_);
    net_counters_ = udpm_->counters();
    return rc;
  }

  // The datagrams refused before any node saw them, in every node's status.
  void reportTransportCounters() {
    if (!udpm_) return;
    net::ReceiverCounters c;
    {
      std::lock_guard<std::mutex> lock(net_mutex_);
      c = net_counters_;
    }
    for (Node* n : nodes_) {
      n->setTransportCounter("datagrams", static_cast<int64_t>(c.datagrams));
      n->setTransportCounter("refused",
                             static_cast<int64_t>(c.reassembly.refusedTotal() + c.truncated));
      n->setTransportCounter("not_allowed", static_cast<int64_t>(c.not_allowed));
      n->setTransportCounter("not_signed", static_cast<int64_t>(c.not_signed));
      for (size_t r = 0; r < c.reassembly.refused.size(); ++r) {
        if (c.reassembly.refused[r] == 0) continue;
        n->setTransportCounter(
            std::string("refused_") + net::refusalName(static_cast<net::Refusal>(r)),
            static_cast<int64_t>(c.reassembly.refused[r]));
      }
    }
  }

  void receiveBuffered() {
    if (options_.wake_on_message) return;
    int rc = 0;
    while ((rc = handleTimeout(0)) > 0) {
    }
    if (failed(rc)) lcm_failed_ = true;
  }

  void dispatch(const Message& m) {
    const auto it = subscribers_.find(m.channel);
    if (it == subscribers_.end()) return;
    for (Node* n : it->second) {
      Outbox out;
      n->receive(m, out);
      publishAll(lcm_, out.take(), options_.auth.get());
    }
  }

  void tickNodes() {
    reportTransportCounters();
    const int64_t now = wallUtime();
    for (Node* n : nodes_) {
      Outbox out;
      n->tick(now, out);
      publishAll(lcm_, out.take(), options_.auth.get());
    }
  }

  // Counts what the full queue refused (each node's `dropped`) and says the total on stderr,
  // at most once a second (a storm would print every tick) and once more at the end.
  void countDropped(bool final = false) {
    for (const auto& [channel, d] : inbox_.takeDropped()) {
      dropped_total_ += d;
      for (Node* n : subscribers_[channel]) n->countLostInput(d);
    }
    const auto now = std::chrono::steady_clock::now();
    if (dropped_total_ != dropped_said_ && (final || now >= next_drop_report_)) {
      std::cerr << "receive queue full: " << dropped_total_ << " messages dropped so far\n";
      dropped_said_ = dropped_total_;
      next_drop_report_ = now + std::chrono::seconds(1);
    }
  }

  lcm::LCM& lcm_;
  const std::vector<Node*>& nodes_;
  const LiveOptions& options_;
  Inbox inbox_;
  RawHandler handler_;
  std::unique_ptr<net::UdpmReceiver> udpm_;  // udpm:// URLs: our receive path, not liblcm's
  std::mutex net_mutex_;
  net::ReceiverCounters net_counters_;
  std::map<std::string, std::vector<Node*>> subscribers_;
  std::vector<lcm::Subscription*> subscriptions_;
  std::thread receiver_;
  std::atomic<bool> receiving_{true};
  std::atomic<bool> lcm_failed_{false};
  int64_t dropped_total_ = 0;
  int64_t dropped_said_ = 0;
  std::chrono::steady_clock::time_point next_drop_report_{};
  SdNotifier notifier_;
};

}  // namespace

namespace {

// The wall clock read once, then advanced by the monotonic clock: a clock step (NTP at boot
// on a Pi without RTC) does not make time jump inside a running process.
struct WallEpoch {
  std::chrono::steady_clock::time_point steady0 = std::chrono::steady_clock::now();
  int64_t wall0_us = std::chrono::duration_cast<std::chrono::microseconds>(
                         std::chrono::system_clock::now().time_since_epoch())
                         .count();
};
const WallEpoch& wallEpoch() {
  static const WallEpoch epoch;
  return epoch;
}

}  // namespace

int64_t wallUtime() {
  const WallEpoch& e = wallEpoch();
  return e.wall0_us + std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::steady_clock::now() - e.steady0)
                          .count();
}

int64_t wallMinusMonotonicNs() {
  // steady_clock is CLOCK_MONOTONIC on Linux (libstdc++).
  const WallEpoch& e = wallEpoch();
  return e.wall0_us * 1000 -
         std::chrono::duration_cast<std::chrono::nanoseconds>(e.steady0.time_since_epoch()).count();
}

void installStopSignals() {
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  std::signal(SIGHUP, onSignal);  // a closed terminal or ssh session stops us cleanly too
}

bool stopRequested() { return g_stop; }

void publishAll(lcm::LCM& lcm, const std::vector<Message>& messages, const net::MessageAuth* auth) {
  // A sweep leaves as a burst of ~48 kB chunks; back to back they overflow a receiver's
  // default socket buffer (~208 kB) and whole chunks are lost. Pace large messages.
  constexpr size_t kLargeMessageBytes = 16 * 1024;
  for (size_t i = 0; i < messages.size(); ++i) {
    const auto& m = messages[i];
    if (auth) {
      const std::vector<uint8_t> signed_data = auth->sign(m.channel, m.data.data(), m.data.size());
      lcm.publish(m.channel, signed_data.data(), static_cast<unsigned int>(signed_data.size()));
    } else {
      lcm.publish(m.channel, m.data.data(), static_cast<unsigned int>(m.data.size()));
    }
    if (m.data.size() >= kLargeMessageBytes && i + 1 < messages.size()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
}

int runLive(lcm::LCM& lcm, const std::vector<Node*>& nodes, const LiveOptions& options) {
  if (!lcm.good()) {
    std::cerr << "LCM initialisation failed\n";
    return kExitDeviceIo;
  }
  const std::string process = options.process.empty() ? thisProcessName() : options.process;
  for (Node* n : nodes) n->setProcess(process);
  std::unique_ptr<LiveRun> live;
  try {
    live = std::make_unique<LiveRun>(lcm, nodes, options);
  } catch (const std::exception& e) {
    std::cerr << "LCM receive: " << e.what() << "\n";
    return kExitDeviceIo;
  }
  LiveRun& run = *live;
  run.subscribe();
  run.startReceiver();
  run.loop();
  if (!run.finish()) {
    std::cerr << "LCM receive failed: stopped\n";
    return kExitDeviceIo;
  }
  return 0;
}

}  // namespace sweepmap
