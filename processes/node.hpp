// The shape every sweepmap process shares: a Node takes encoded LCM messages (and, for
// nodes that drive devices, the passing of time) and returns messages to publish. It
// does no transport I/O and never reads the wall clock for its results, so the same
// object runs live over LCM (live_runner.hpp) and offline in a discrete-event loop
// (offline_bus.hpp), with identical outputs.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "processes/message_codec.hpp"
#include "processes/stamp_guard.hpp"

namespace sweepmap {

// One message on a channel. `utime` is when it was published/received [us]: the log
// event's timestamp, not a field of the message.
struct Message {
  int64_t utime = 0;
  std::string channel;
  std::vector<uint8_t> data;
};

class Outbox {
 public:
  template <class T>
  void publish(const std::string& channel, int64_t utime, const T& msg) {
    Message m;
    m.utime = utime;
    m.channel = channel;
    m.data = encodeMessage(msg);
    messages_.push_back(std::move(m));
  }
  void push(Message m) { messages_.push_back(std::move(m)); }
  std::vector<Message> take() {
    std::vector<Message> out;
    out.swap(messages_);
    return out;
  }
  bool empty() const { return messages_.empty(); }

 private:
  std::vector<Message> messages_;
};

// Decodes an lcm-gen type (message_codec.hpp); false when the bytes are not exactly one
// valid message.
template <class T>
bool decodeMessage(const Message& m, T* out) {
  return decodeMessage(m.data.data(), m.data.size(), out);
}

class Node {
 public:
  explicit Node(std::string name);
  virtual ~Node() = default;
  const std::string& name() const { return name_; }
  std::string statusChannel() const;

  virtual std::vector<std::string> subscriptions() const = 0;

  // Handles one message. Never throws: bad input is counted and reported.
  void receive(const Message& msg, Outbox& out);
  // Lets time pass (device polling, timers); publishes the status at 1 Hz.
  void tick(int64_t now_utime, Outbox& out);
  // End of input: flush what is pending.
  virtual void finish(int64_t now_utime, Outbox& out) {}

  int64_t counter(const std::string& name) const;
  // Input lost before it reached the node (e.g. the live receive queue was full).
  void countLostInput(int64_t n) { counters_["dropped"] += n; }
  // The receive path's own counters (datagrams refused before any node saw them), shown in
  // this node's status as `net_<name>`.
  void setTransportCounter(const std::string& name, int64_t value) {
    counters_["net_" + name] = value;
  }
  void publishStatus(int64_t now_utime, Outbox& out);
  bool failed() const { return failed_; }
  // The process this node runs in, named in its status (process_status_t.process) so that a
  // monitor shows one row per process; the node's own name until set (runLive sets it).
  void setProcess(std::string process) { process_ = std::move(process); }

 protected:
  virtual void handle(const Message& msg, Outbox& out) = 0;
  virtual void advance(int64_t now_utime, Outbox& out) {}
  // A message refused before handle() (invalid against its schema, or its stamp off its
  // stream): counted already; a node whose estimate depends on that input may say so.
  virtual void onRefused(const Message& msg) {}
  void count(const std::string& name, int64_t n = 1) { counters_[name] += n; }
  // For counters kept elsewhere (a device driver's): the status shows `value`.
  void setCounter(const std::string& name, int64_t value) { counters_[name] = value; }
  // An event worth telling (printed rate-limited, kept as the status detail), not counted.
  void reportEvent(const std::string& what);
  // Reports bad input: counted under `counter`, printed rate-limited, kept as the status detail.
  void reportError(const std::string& counter, const std::string& what);
  void setFailed(const std::string& what);
  // A lasting condition (not an error): the status says DEGRADED with `why` as its detail
  // until clearDegraded(). Each change is reported once.
  void setDegraded(const std::string& why);
  void clearDegraded(const std::string& what);
  bool degraded() const { return !degraded_.empty(); }

 private:
  std::string name_;
  std::string process_;
  std::map<std::string, int64_t> counters_;
  StampGuard stamps_;
  std::string detail_;
  bool failed_ = false;
  std::string degraded_;
  int64_t next_status_utime_ = 0;
  int64_t errors_printed_ = 0;
};

}  // namespace sweepmap
