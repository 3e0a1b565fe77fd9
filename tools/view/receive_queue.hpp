// The live view's messages between its LCM receiver and the thread that feeds the view. The
// receiver only copies a datagram's message in, so the socket is read as fast as the network
// delivers, whatever the view is doing meanwhile (sending a page a 30 MB state, converting a
// cloud for Foxglove, waiting for the lock a page's snapshot holds). Without it the kernel's
// receive buffer (a few MB, tens of cloud chunks) overflowed while the view was busy, and the
// chunks were lost uncounted (a third of a 2 M-point run at load 2-4). Bounded in bytes: when
// full, the message arriving is dropped and counted.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>

#include "processes/node.hpp"

namespace sweepmap {

class ReceiveQueue {
 public:
  explicit ReceiveQueue(size_t max_bytes) : max_bytes_(max_bytes) {}

  // False (and counted) when the message does not fit.
  bool push(Message m) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const size_t n = sizeOf(m);
      if (bytes_ + n > max_bytes_) {
        ++dropped_;
        return false;
      }
      bytes_ += n;
      peak_bytes_ = std::max(peak_bytes_, bytes_);
      messages_.push_back(std::move(m));
    }
    ready_.notify_one();
    return true;
  }

  // The oldest message; false when none came within `timeout`.
  bool pop(Message* m, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!ready_.wait_for(lock, timeout, [this] { return !messages_.empty(); })) return false;
    *m = std::move(messages_.front());
    messages_.pop_front();
    bytes_ -= sizeOf(*m);
    return true;
  }

  int64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  size_t peakBytes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return peak_bytes_;
  }

 private:
  static size_t sizeOf(const Message& m) { return m.data.size() + m.channel.size() + 64; }

  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<Message> messages_;
  size_t max_bytes_;
  size_t bytes_ = 0;
  size_t peak_bytes_ = 0;
  int64_t dropped_ = 0;
};

}  // namespace sweepmap
