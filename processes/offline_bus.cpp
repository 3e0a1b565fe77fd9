#include "processes/offline_bus.hpp"

#include <deque>

namespace sweepmap {

void OfflineBus::attach(Node* node) {
  nodes_.push_back(node);
  for (const auto& ch : node->subscriptions()) subscribers_[ch].push_back(node);
}

void OfflineBus::route(Outbox& out) {
  std::deque<Message> queue;
  for (auto& m : out.take()) queue.push_back(std::move(m));
  while (!queue.empty()) {
    Message m = std::move(queue.front());
    queue.pop_front();
    if (sink_) sink_(m);
    const auto it = subscribers_.find(m.channel);
    if (it == subscribers_.end()) continue;
    for (Node* n : it->second) {
      Outbox next;
      n->receive(m, next);
      for (auto& r : next.take()) queue.push_back(std::move(r));
    }
  }
}

void OfflineBus::deliver(const Message& msg) {
  const auto it = subscribers_.find(msg.channel);
  if (it == subscribers_.end()) return;
  for (Node* n : it->second) {
    Outbox out;
    n->receive(msg, out);
    route(out);
  }
}

void OfflineBus::publish(const Message& msg) {
  Outbox out;
  out.push(msg);
  route(out);
}

void OfflineBus::tick(int64_t now_utime) {
  for (Node* n : nodes_) {
    Outbox out;
    n->tick(now_utime, out);
    route(out);
  }
}

void OfflineBus::finish(int64_t now_utime) {
  for (Node* n : nodes_) {
    Outbox out;
    n->finish(now_utime, out);
    n->publishStatus(now_utime, out);
    route(out);
  }
}

}  // namespace sweepmap
