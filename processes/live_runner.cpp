#include "processes/live_runner.hpp"

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <condition_variable>
#include <csignal>
#include <deque>
#include <iostream>
#include <map>
#include <mutex>
#include <thread>

namespace sweepmap {
namespace {

std::atomic<bool> g_stop{false};

void onSignal(int) { g_stop = true; }

class Inbox {
 public:
  Inbox(size_t capacity, size_t capacity_bytes) : capacity_(capacity), capacity_bytes_(capacity_bytes) {}
  void push(Message m, bool wake) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= capacity_ || bytes_ + m.data.size() > capacity_bytes_) {
      ++dropped_[m.channel];
      return;
    }
    bytes_ += m.data.size();
    queue_.push_back(std::move(m));
    if (wake) cv_.notify_one();
  }
  // Waits until a message is there or `deadline`; returns everything queued.
  std::deque<Message> popUntil(std::chrono::steady_clock::time_point deadline) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_until(lock, deadline, [&] { return !queue_.empty(); });
    std::deque<Message> out;
    out.swap(queue_);
    bytes_ = 0;
    return out;
  }
  std::map<std::string, int64_t> takeDropped() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::map<std::string, int64_t> d;
    d.swap(dropped_);
    return d;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Message> queue_;
  size_t capacity_;
  size_t capacity_bytes_;
  size_t bytes_ = 0;
  std::map<std::string, int64_t> dropped_;
};

class RawHandler {
 public:
  RawHandler(Inbox* inbox, bool wake) : inbox_(inbox), wake_(wake) {}
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    Message m;
    m.utime = wallUtime();
    m.channel = channel;
    const auto* p = static_cast<const uint8_t*>(rbuf->data);
    m.data.assign(p, p + rbuf->data_size);
    inbox_->push(std::move(m), wake_);
  }

 private:
  Inbox* inbox_;
  bool wake_;
};

}  // namespace

int64_t wallUtime() {
  // The wall clock read once, then advanced by the monotonic clock: a clock step (NTP at
  // boot on a Pi without RTC) does not make time jump inside a running process.
  static const auto steady0 = std::chrono::steady_clock::now();
  static const int64_t wall0 = std::chrono::duration_cast<std::chrono::microseconds>(
                                   std::chrono::system_clock::now().time_since_epoch())
                                   .count();
  return wall0 + std::chrono::duration_cast<std::chrono::microseconds>(
                     std::chrono::steady_clock::now() - steady0)
                     .count();
}

void installStopSignals() {
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
}

bool stopRequested() { return g_stop; }

void publishAll(lcm::LCM& lcm, const std::vector<Message>& messages) {
  // A sweep leaves as a burst of ~48 kB chunks; back to back they overflow a receiver's
  // default socket buffer (~208 kB) and whole chunks are lost. Pace large messages.
  constexpr size_t kLargeMessageBytes = 16 * 1024;
  for (size_t i = 0; i < messages.size(); ++i) {
    const auto& m = messages[i];
    lcm.publish(m.channel, m.data.data(), static_cast<unsigned int>(m.data.size()));
    if (m.data.size() >= kLargeMessageBytes && i + 1 < messages.size()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
}

int runLive(lcm::LCM& lcm, const std::vector<Node*>& nodes, const LiveOptions& options) {
  if (!lcm.good()) {
    std::cerr << "LCM initialisation failed\n";
    return 2;
  }
  Inbox inbox(options.queue_capacity, options.queue_capacity_bytes);
  RawHandler handler(&inbox, options.wake_on_message);
  std::map<std::string, std::vector<Node*>> subscribers;
  for (Node* n : nodes) {
    for (const auto& ch : n->subscriptions()) {
      if (subscribers[ch].empty()) lcm.subscribe(ch, &RawHandler::onMessage, &handler);
      subscribers[ch].push_back(n);
    }
  }

  const auto dispatch = [&](const Message& m) {
    const auto it = subscribers.find(m.channel);
    if (it == subscribers.end()) return;
    for (Node* n : it->second) {
      Outbox out;
      n->receive(m, out);
      publishAll(lcm, out.take());
    }
  };

  std::atomic<bool> receiving{true};
  std::atomic<bool> lcm_failed{false};
  // Waking per message: a receiver thread hands each message over at once. Otherwise the
  // worker itself takes what LCM has buffered at each tick, so a message costs no thread
  // switch of ours (LCM's own receive thread still wakes for it).
  std::thread receiver;
  if (options.wake_on_message) {
    receiver = std::thread([&] {
      while (receiving) {
        if (lcm.handleTimeout(50) < 0) {
          lcm_failed = true;
          break;
        }
      }
    });
  }
  const auto receiveBuffered = [&] {
    if (options.wake_on_message) return;
    int rc = 0;
    while ((rc = lcm.handleTimeout(0)) > 0) {
    }
    if (rc < 0) lcm_failed = true;
  };

  const auto period = std::chrono::milliseconds(std::max(1, options.tick_period_ms));
  auto next_tick = std::chrono::steady_clock::now();
  int64_t dropped_total = 0;
  while (!g_stop && !lcm_failed) {
    receiveBuffered();
    for (const Message& m : inbox.popUntil(next_tick)) dispatch(m);
    if (std::chrono::steady_clock::now() >= next_tick) {
      const int64_t now = wallUtime();
      for (Node* n : nodes) {
        Outbox out;
        n->tick(now, out);
        publishAll(lcm, out.take());
      }
      next_tick += period;
      if (std::chrono::steady_clock::now() > next_tick + 100 * period) {
        next_tick = std::chrono::steady_clock::now();  // fell behind: do not burst
      }
      for (const auto& [channel, d] : inbox.takeDropped()) {
        dropped_total += d;
        for (Node* n : subscribers[channel]) n->countLostInput(d);
        std::cerr << "receive queue full: " << dropped_total << " messages dropped so far\n";
      }
      if (options.should_stop && options.should_stop()) break;
    }
  }
  // Drain what arrived before the stop, then let the nodes flush.
  auto drain_until = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
  if (!options.wake_on_message) {
    while (!lcm_failed && std::chrono::steady_clock::now() < drain_until) {
      if (lcm.handleTimeout(20) < 0) lcm_failed = true;
    }
    drain_until = std::chrono::steady_clock::now();
  }
  for (const Message& m : inbox.popUntil(drain_until)) dispatch(m);
  const int64_t now = wallUtime();
  for (Node* n : nodes) {
    Outbox out;
    n->finish(now, out);
    n->publishStatus(now, out);
    publishAll(lcm, out.take());
  }
  receiving = false;
  if (receiver.joinable()) receiver.join();
  if (lcm_failed) {
    std::cerr << "LCM receive failed: stopped\n";
    return 2;
  }
  return 0;
}

}  // namespace sweepmap
