// What the node tests share: a message as a node receives it from the bus.
#pragma once

#include <string>

#include "processes/node.hpp"

namespace sweepmap {
namespace test {

// `msg` encoded on channel `ch` (utime 0), as an Outbox publishes it.
template <class T>
Message encode(const std::string& ch, const T& msg) {
  Outbox o;
  o.publish(ch, 0, msg);
  return o.take().front();
}

}  // namespace test
}  // namespace sweepmap
