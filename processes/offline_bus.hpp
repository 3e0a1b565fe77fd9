// Discrete-event loop for simulation and replay: all nodes in one thread on a virtual
// clock. A delivered message reaches its subscribers in attach order; what they publish
// is delivered in turn, in publication order, before the next input. The sink sees every
// message (inputs excluded) for writing logs. Same inputs -> same outputs, byte for byte.
#pragma once

#include <functional>
#include <map>
#include <vector>

#include "processes/node.hpp"

namespace sweepmap {

class OfflineBus {
 public:
  using Sink = std::function<void(const Message&)>;

  void attach(Node* node);
  void setSink(Sink sink) { sink_ = std::move(sink); }

  // Delivers an input message (not passed to the sink).
  void deliver(const Message& msg);
  // Lets every node see time `now_utime`, then routes what they published.
  void tick(int64_t now_utime);
  // Ends the input: every node's finish(), then routing.
  void finish(int64_t now_utime);
  // Publishes a message from outside any node (e.g. simulated ground truth).
  void publish(const Message& msg);

 private:
  void route(Outbox& out);

  std::vector<Node*> nodes_;
  std::map<std::string, std::vector<Node*>> subscribers_;
  Sink sink_;
};

}  // namespace sweepmap
