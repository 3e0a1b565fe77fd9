// The live runner over LCM's in-process memq:// provider: every message reaches the node,
// in order, whether the worker wakes for each message or only at its ticks.
#include <gtest/gtest.h>

#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "sweepmap/map_save_t.hpp"
#include "sweepmap/process_status_t.hpp"

namespace sweepmap {
namespace {

class RecordingNode : public Node {
 public:
  RecordingNode() : Node("recorder") {}
  std::vector<std::string> subscriptions() const override { return {"IN"}; }
  std::vector<int> seen;

 protected:
  void handle(const Message& m, Outbox&) override {
    map_save_t r;
    if (decodeMessage(m, &r)) seen.push_back(static_cast<int>(r.utime));
  }
};

// Message i: a valid LCM message (a node sees nothing else), numbered by its utime.
void publishNumbered(lcm::LCM& lcm, int i) {
  map_save_t m{};
  m.utime = i;
  lcm.publish("IN", &m);
}

void runWith(bool wake_on_message) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  RecordingNode node;
  LiveOptions options("memq://");
  options.tick_period_ms = 10;
  options.wake_on_message = wake_on_message;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  options.should_stop = [&] {
    return node.seen.size() >= 100 || std::chrono::steady_clock::now() > give_up;
  };
  std::thread publisher([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // after runLive subscribed
    for (int i = 0; i < 100; ++i) {
      publishNumbered(lcm, i);
      if (i % 10 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(3));
    }
  });
  EXPECT_EQ(runLive(lcm, {&node}, options), 0);
  publisher.join();
  ASSERT_EQ(node.seen.size(), 100u);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(node.seen[i], i);
}

TEST(LiveRunner, WakingPerMessageDeliversEverythingInOrder) { runWith(true); }

TEST(LiveRunner, WakingOnlyAtTicksDeliversEverythingInOrder) { runWith(false); }

// The receive queue is bounded: 100 messages waiting in LCM when the worker takes them at a
// tick (the node publishes them itself at its first tick), with room for 10 — the first 10
// reach the node, the other 90 are dropped and counted in the node's `dropped` (its status).
class FloodingNode : public RecordingNode {
 public:
  explicit FloodingNode(lcm::LCM* lcm) : lcm_(lcm) {}
  int ticks = 0;

 protected:
  void advance(int64_t, Outbox&) override {
    if (++ticks != 1) return;
    for (int i = 0; i < 100; ++i) publishNumbered(*lcm_, i);
  }

 private:
  lcm::LCM* lcm_;
};

TEST(LiveRunner, AFullQueueDropsAndCountsTheRest) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  FloodingNode node(&lcm);
  LiveOptions options("memq://");
  options.wake_on_message = false;
  options.queue_capacity = 10;
  options.should_stop = [&] { return node.ticks >= 3; };
  EXPECT_EQ(runLive(lcm, {&node}, options), 0);
  ASSERT_EQ(node.seen.size(), 10u);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(node.seen[i], i);
  EXPECT_EQ(node.counter("dropped"), 90);
  EXPECT_EQ(node.counter("messages_in"), 10);
}

// The status of a node names the process it runs in (so that `sweepmap status` shows one row
// per process): its own name offline, this executable's name (less "sweepmap-") or
// LiveOptions::process live.
std::string processInStatus(Node& node) {
  Outbox out;
  node.publishStatus(0, out);
  process_status_t s;
  const std::vector<Message> sent = out.take();
  EXPECT_EQ(sent.size(), 1u);
  EXPECT_TRUE(!sent.empty() && decodeMessage(sent.front(), &s));
  return s.process;
}

TEST(LiveRunner, NodesNameTheirProcessInTheirStatus) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  RecordingNode node;
  EXPECT_EQ(processInStatus(node), "recorder");
  LiveOptions options("memq://");
  options.should_stop = [] { return true; };
  EXPECT_EQ(runLive(lcm, {&node}, options), 0);
  EXPECT_EQ(processInStatus(node), "test_processes");
  options.process = "lidar";
  EXPECT_EQ(runLive(lcm, {&node}, options), 0);
  EXPECT_EQ(processInStatus(node), "lidar");
}

// A process's bounds come from its rig's network.* keys, --queue-capacity over the queue's.
TEST(LiveOptions, BoundsFromTheRigsNetworkKeys) {
  CommonOptions o;
  o.lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  o.network.queue_messages = 7;
  o.network.queue_mib = 2;
  o.network.max_message_mib = 1;
  o.network.pending_messages_per_sender = 3;
  o.network.pending_mib_per_sender = 0.5;
  o.network.pending_mib = 4;
  o.network.max_senders = 5;
  o.network.fragment_timeout_s = 0.25;
  const LiveOptions l = liveOptions(o);
  EXPECT_EQ(l.lcm_url, o.lcm_url);
  EXPECT_EQ(l.queue_capacity, 7u);
  EXPECT_EQ(l.queue_capacity_bytes, 2u << 20);
  EXPECT_EQ(l.reassembly.max_message_bytes, 1u << 20);
  EXPECT_EQ(l.reassembly.max_pending_per_sender, 3u);
  EXPECT_EQ(l.reassembly.max_pending_bytes_per_sender, 1u << 19);
  EXPECT_EQ(l.reassembly.max_pending_bytes, 4u << 20);
  EXPECT_EQ(l.reassembly.max_senders, 5u);
  EXPECT_EQ(l.reassembly.fragment_timeout_us, 250000);
  o.queue_capacity = 3;  // --queue-capacity
  EXPECT_EQ(liveOptions(o).queue_capacity, 3u);
}

}  // namespace
}  // namespace sweepmap
