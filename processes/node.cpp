#include "processes/node.hpp"

#include <algorithm>
#include <cctype>
#include <iostream>

#include "core/lcm_schema.hpp"
#include "sweepmap/process_status_t.hpp"

namespace sweepmap {

Node::Node(std::string name) : name_(std::move(name)) {}

std::string Node::statusChannel() const {
  std::string upper = name_;
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return "STATUS_" + upper;
}

void Node::receive(const Message& msg, Outbox& out) {
  count("messages_in");
  // Nothing that arrives is trusted: every message is checked against its type's .lcm schema
  // (lengths, counts, strings, finite numbers, enums) before any field is read, and an invalid
  // one never reaches the node (counted per channel, the reason in the status detail).
  if (const std::string why = LcmSchema::builtIn().validate(msg.data.data(), msg.data.size());
      !why.empty()) {
    count("invalid_" + msg.channel);
    reportError("invalid", msg.channel + ": " + why);
    onRefused(msg);
    return;
  }
  // Its own stamp against this node's clock and the channel's stream (stamp_guard.hpp).
  int64_t stamp = 0;
  for (size_t k = 8; k < 16; ++k)
    stamp = static_cast<int64_t>((static_cast<uint64_t>(stamp) << 8) | msg.data[k]);
  if (std::string why; !stamps_.admit(msg.channel, stamp, msg.utime, &why)) {
    count("stamp_refused_" + msg.channel);
    reportError("stamp_refused", why);
    onRefused(msg);
    return;
  }
  try {
    handle(msg, out);
  } catch (const std::exception& e) {
    reportError("errors", "on " + msg.channel + ": " + e.what());
  }
}

void Node::tick(int64_t now_utime, Outbox& out) {
  try {
    advance(now_utime, out);
  } catch (const std::exception& e) {
    reportError("errors", std::string("in tick: ") + e.what());
  }
  if (now_utime >= next_status_utime_) {
    publishStatus(now_utime, out);
    next_status_utime_ = now_utime + 1000000;
  }
}

int64_t Node::counter(const std::string& name) const {
  const auto it = counters_.find(name);
  return it == counters_.end() ? 0 : it->second;
}

void Node::reportError(const std::string& counter, const std::string& what) {
  count(counter);
  reportEvent(what);
}

void Node::reportEvent(const std::string& what) {
  detail_ = what;
  // Rate limit by count (deterministic): the first 10, then every 1000th.
  ++errors_printed_;
  if (errors_printed_ <= 10 || errors_printed_ % 1000 == 0) {
    std::cerr << name_ << ": " << what;
    if (errors_printed_ == 10) std::cerr << " (further errors are printed every 1000th)";
    std::cerr << "\n";
  }
}

void Node::setFailed(const std::string& what) {
  failed_ = true;
  detail_ = what;
  std::cerr << name_ << ": FAILED: " << what << "\n";
}

void Node::setDegraded(const std::string& why) {
  if (degraded_ == why) return;
  degraded_ = why;
  reportEvent(why);
}

void Node::clearDegraded(const std::string& what) {
  if (degraded_.empty()) return;
  degraded_.clear();
  reportEvent(what);
}

void Node::publishStatus(int64_t now_utime, Outbox& out) {
  process_status_t s;
  s.utime = now_utime;
  s.process = process_.empty() ? name_ : process_;
  const bool errors = counter("errors") + counter("dropped") + counter("invalid") > 0;
  s.health =
      failed_ ? process_status_t::FAILED
              : (errors || !degraded_.empty() ? process_status_t::DEGRADED : process_status_t::OK);
  s.detail = !failed_ && !degraded_.empty() ? degraded_ : detail_;
  for (const auto& [k, v] : counters_) {
    s.counter_names.push_back(k);
    s.counter_values.push_back(v);
  }
  s.ncounters = static_cast<int32_t>(s.counter_names.size());
  out.publish(statusChannel(), now_utime, s);
}

}  // namespace sweepmap
