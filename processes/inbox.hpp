// The bounded queue between a receive thread and a worker (the live runner's nodes,
// `sweepmap record`'s writer): bounded in messages and in bytes, and a message that finds it
// full is dropped and counted per channel, never waited for (LCM's logger does the same: its
// receive callback only enqueues).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <string>

#include "processes/node.hpp"

namespace sweepmap {

class Inbox {
 public:
  Inbox(size_t capacity, size_t capacity_bytes)
      : capacity_(capacity), capacity_bytes_(capacity_bytes) {}

  // Queues `m`, or drops and counts it when either bound would be passed. `wake`: wake a
  // worker waiting in popUntil.
  void push(Message m, bool wake) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= capacity_ || bytes_ + m.data.size() > capacity_bytes_) {
      ++dropped_[m.channel];
      ++dropped_total_;
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
  // Everything queued, without waiting.
  std::deque<Message> take() { return popUntil(std::chrono::steady_clock::time_point::min()); }

  // The drops per channel since the last call.
  std::map<std::string, int64_t> takeDropped() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::map<std::string, int64_t> d;
    d.swap(dropped_);
    return d;
  }
  // All drops since the start.
  int64_t droppedTotal() {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_total_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Message> queue_;
  size_t capacity_;
  size_t capacity_bytes_;
  size_t bytes_ = 0;
  std::map<std::string, int64_t> dropped_;
  int64_t dropped_total_ = 0;
};

}  // namespace sweepmap
