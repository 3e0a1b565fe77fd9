#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "net/lcm_datagram.hpp"
#include "processes/assembler_node.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "sweepmap/sweep_status_t.hpp"

namespace sweepmap {
namespace {

class AssemblerNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    rig_.lidar.beam_count = 9;
    rig_.assembler.chunk_points = 50;
  }
  Message scanMsg(int j, float range = 2.0f, bool intensity = false) const {
    Scan2D s;
    s.utime = 1000000 + 25000 * j;
    s.seq = j;
    s.angle_min_rad = -1.0;
    s.angle_increment_rad = 0.25;
    s.time_increment_ns = 17361;
    s.range_min_m = 0.06;
    s.range_max_m = 10.0;
    s.ranges_m.assign(9, range);
    // Ray i of scan j reads 100 j + i: each point's intensity names its ray.
    for (int i = 0; intensity && i < 9; ++i) s.intensities.push_back(float(100 * j + i));
    return encode(channels::kLidarScan, s.utime, toLcm(s));
  }
  Message windowMsg(int64_t id, int64_t start, int64_t end) const {
    scan_window_t w;
    w.utime = end;
    w.sweep_id = id;
    w.mode = 1;
    w.start_utime = start;
    w.end_utime = end;
    w.angular_velocity_rad_s = M_PI;
    w.sweep_angle_rad = M_PI;
    w.action_sequence = scan_window_t::IMPROVED;
    w.accel_overlap = false;
    return encode(channels::kScanWindow, end, w);
  }
  template <class T>
  static Message encode(const std::string& ch, int64_t utime, const T& msg) {
    Outbox o;
    o.publish(ch, utime, msg);
    return o.take().front();
  }
  // Feeds messages in order; returns the decoded chunks.
  std::vector<cloud_chunk_t> feed(const std::vector<Message>& msgs, AssemblerNode* node) {
    std::vector<cloud_chunk_t> chunks;
    for (const auto& m : msgs) {
      Outbox out;
      node->receive(m, out);
      for (const auto& o : out.take()) {
        if (o.channel != channels::kSweepCloud) continue;
        cloud_chunk_t c;
        EXPECT_TRUE(decodeMessage(o, &c));
        chunks.push_back(c);
      }
    }
    return chunks;
  }
  RotatingLidarConfig rig_;
};

TEST_F(AssemblerNodeTest, WindowAssembledOnceAScanPassesItsEnd) {
  AssemblerNode node(rig_);
  std::vector<Message> msgs;
  for (int j = 0; j < 8; ++j) msgs.push_back(scanMsg(j));
  msgs.push_back(windowMsg(0, 1000000, 1000000 + 25000 * 8));
  auto chunks = feed(msgs, &node);
  EXPECT_TRUE(chunks.empty()) << "assembled before a scan at or after the window end";
  chunks = feed({scanMsg(8)}, &node);
  ASSERT_EQ(chunks.size(), 2u);  // 8 scans x 9 rays = 72 points in chunks of 50
  EXPECT_EQ(chunks[0].total_points, 72);
  EXPECT_EQ(chunks[0].npoints + chunks[1].npoints, 72);
  EXPECT_EQ(chunks[1].chunk_index, 1);
  EXPECT_EQ(chunks[1].chunk_count, 2);
  EXPECT_EQ(chunks[0].frame, "O'");  // no plate in this data
  EXPECT_FALSE(chunks[0].corrected);
}

// The intensity of each ray reaches its point's place in the chunks (split across chunks),
// and a lidar without intensity gives chunks without them.
TEST_F(AssemblerNodeTest, ChunksCarryEachPointsIntensity) {
  for (const bool intensity : {true, false}) {
    AssemblerNode node(rig_);
    std::vector<Message> msgs;
    for (int j = 0; j < 9; ++j) msgs.push_back(scanMsg(j, 2.0f, intensity));
    msgs.push_back(windowMsg(0, 1000000, 1000000 + 25000 * 8));
    const auto chunks = feed(msgs, &node);
    ASSERT_EQ(chunks.size(), 2u);
    std::vector<float> got;
    for (const auto& c : chunks) {
      EXPECT_EQ(c.nintensities, intensity ? c.npoints : 0);
      EXPECT_TRUE(validateChunk(c).empty()) << validateChunk(c);
      got.insert(got.end(), c.intensities.begin(), c.intensities.end());
    }
    std::vector<float> want;
    for (int j = 0; intensity && j < 8; ++j) {
      for (int i = 0; i < 9; ++i) want.push_back(float(100 * j + i));
    }
    EXPECT_EQ(got, want);
  }
}

// The largest chunk a rig allows (assembler.chunk_points <= 4000, rigs/rotating_lidar.cpp), with
// its intensities, is still one LCM datagram on SWEEP_CLOUD.
TEST(CloudChunk, TheLargestChunkWithIntensitiesIsOneDatagram) {
  AssembledSweep sweep;
  sweep.points.assign(4000, Eigen::Vector3f(1.0f, 2.0f, 3.0f));
  sweep.intensities.assign(4000, 100.0f);
  const auto chunks = toChunks(sweep, 4000);
  ASSERT_EQ(chunks.size(), 1u);
  ASSERT_EQ(chunks[0].nintensities, 4000);
  const size_t bytes =
      encodeMessage(chunks[0]).size() + std::string(channels::kSweepCloud).size() + 1;
  EXPECT_LE(bytes, net::kLcmShortMessageMaxBytes);
}

TEST(CloudChunk, IntensitiesNeitherNoneNorOnePerPointAreInvalid) {
  cloud_chunk_t c{};
  c.chunk_count = 1;
  c.total_points = c.npoints = 2;
  c.xyz_m = {{1, 2, 3}, {4, 5, 6}};
  EXPECT_EQ(validateChunk(c), "");
  c.nintensities = 1;
  c.intensities = {7};
  EXPECT_EQ(validateChunk(c), "nintensities 1 is neither 0 nor npoints 2");
  c.nintensities = 2;
  c.intensities = {7, 8};
  EXPECT_EQ(validateChunk(c), "");
}

// Live, the window message may arrive before or after the scans it covers.
TEST_F(AssemblerNodeTest, OutputIndependentOfChannelInterleaving) {
  std::vector<Message> scans;
  for (int j = 0; j < 12; ++j) scans.push_back(scanMsg(j));
  const Message w = windowMsg(4, 1000000 + 25000 * 2, 1000000 + 25000 * 9);
  AssemblerNode a(rig_), b(rig_);
  std::vector<Message> early = {w};
  early.insert(early.end(), scans.begin(), scans.end());
  std::vector<Message> late = scans;
  late.push_back(w);
  const auto ca = feed(early, &a);
  const auto cb = feed(late, &b);
  ASSERT_EQ(ca.size(), cb.size());
  ASSERT_FALSE(ca.empty());
  for (size_t i = 0; i < ca.size(); ++i) EXPECT_EQ(ca[i].xyz_m, cb[i].xyz_m);
}

TEST_F(AssemblerNodeTest, BadInputIsCountedNotFatal) {
  AssemblerNode node(rig_);
  std::vector<Message> msgs;
  msgs.push_back(scanMsg(0));
  Message garbage{0, channels::kLidarScan, {1, 2, 3, 4, 5}};
  msgs.push_back(garbage);  // malformed bytes
  Message truncated = scanMsg(1);
  truncated.data.resize(truncated.data.size() / 2);
  msgs.push_back(truncated);                                            // truncated message
  msgs.push_back(scanMsg(2, std::numeric_limits<float>::quiet_NaN()));  // NaN ranges
  msgs.push_back(scanMsg(3, std::numeric_limits<float>::infinity()));
  msgs.push_back(scanMsg(4, 1e9f));  // absurd range
  {
    Scan2D s;
    s.utime = 1000000 + 25000 * 5;
    s.range_max_m = 10;
    s.ranges_m.assign(3, 1.0f);     // any ray count is a scan (a sub-range of the field) ...
    s.intensities.assign(2, 1.0f);  // ... but not 2 intensities for 3 rays: wrong length
    msgs.push_back(encode(channels::kLidarScan, s.utime, toLcm(s)));
  }
  msgs.push_back(scanMsg(0));                      // repeated: out of order
  msgs.push_back(windowMsg(0, 2000000, 1000000));  // ends before it starts
  Message bad_window{0, channels::kScanWindow, {0xff, 0xfe}};
  msgs.push_back(bad_window);
  msgs.push_back(scanMsg(6));
  EXPECT_NO_THROW(feed(msgs, &node));
  EXPECT_EQ(node.counter("scans"), 2);
  EXPECT_EQ(node.counter("invalid"), 8);
  EXPECT_EQ(node.counter("dropped"), 1);
  EXPECT_EQ(node.counter("errors"), 0);
}

// One far-future stamp is dropped (by every node's stamp guard, processes/stamp_guard.hpp)
// and does not block later scans; a real clock step (several scans agreeing) restarts
// assembly: the guard lets the third scan of the new clock through, the assembler's own
// check then wants three more before it discards what it holds and starts again.
TEST_F(AssemblerNodeTest, FarFutureStampDoesNotBlockTheStream) {
  AssemblerNode node(rig_);
  std::vector<Message> msgs = {scanMsg(0), scanMsg(1)};
  Message future = scanMsg(2);
  {
    lidar_scan_t s;
    ASSERT_TRUE(decodeMessage(future, &s));
    s.utime += 1000LL * 1000000 * 3600;  // an hour ahead, arriving on time
    future = encode(channels::kLidarScan, scanMsg(2).utime, s);
  }
  msgs.push_back(future);
  for (int j = 3; j < 8; ++j) msgs.push_back(scanMsg(j));
  feed(msgs, &node);
  EXPECT_EQ(node.counter("scans"), 7);
  EXPECT_EQ(node.counter("stamp_refused_LIDAR_SCAN"), 1);
  EXPECT_EQ(node.counter("invalid"), 0);
  EXPECT_EQ(node.counter("clock_resets"), 0);
  // The source restarts with a clock a day behind: after 3 scans it is believed.
  std::vector<Message> later;
  for (int j = 0; j < 6; ++j) {
    Message m = scanMsg(100 + j);
    lidar_scan_t s;
    ASSERT_TRUE(decodeMessage(m, &s));
    s.utime -= 86400LL * 1000000;
    later.push_back(encode(channels::kLidarScan, m.utime, s));
  }
  feed(later, &node);
  EXPECT_EQ(node.counter("stamp_refused_LIDAR_SCAN"), 1 + 2);
  EXPECT_EQ(node.counter("clock_resets"), 1);
  EXPECT_EQ(node.counter("scans"), 7 + 2);
}

TEST_F(AssemblerNodeTest, FinishFlushesIncompleteWindow) {
  AssemblerNode node(rig_);
  std::vector<Message> msgs;
  for (int j = 0; j < 4; ++j) msgs.push_back(scanMsg(j));
  msgs.push_back(windowMsg(0, 1000000, 1000000 + 25000 * 8));
  EXPECT_TRUE(feed(msgs, &node).empty());
  Outbox out;
  node.finish(0, out);
  int chunks = 0;
  for (const auto& m : out.take()) chunks += m.channel == channels::kSweepCloud;
  EXPECT_EQ(chunks, 1);
}

// Scans lost on the way (a gap in their seq) or dropped here as out of order make the
// sweeps whose windows they fall in incomplete: published all the same, and counted. Gaps
// between windows count for no sweep; a lost window shows as a gap in the sweep ids.
TEST_F(AssemblerNodeTest, SweepsWithMissingScansAreCountedIncomplete) {
  const auto t = [](int j) { return 1000000 + 25000 * j; };
  AssemblerNode node(rig_);
  std::vector<int> missing_per_sweep;
  node.setSweepObserver(
      [&](const AssembledSweep& s) { missing_per_sweep.push_back(s.missing_scans); });
  std::vector<Message> msgs;
  // Sweep 0 covers scans 2..8: 1 (before it), 2, 4 and 5 are lost.
  msgs.push_back(windowMsg(0, t(2), t(9)));
  for (int j : {0, 3, 6, 7, 8, 9}) msgs.push_back(scanMsg(j));
  // Scan 10, between the windows, is lost; sweep 1 (scans 12..19) is whole.
  msgs.push_back(windowMsg(1, t(12), t(20)));
  for (int j = 11; j <= 20; ++j) msgs.push_back(scanMsg(j));
  // The window of sweep 2 is lost; sweep 3 (scans 21..27) gets scan 23 after 24: dropped.
  msgs.push_back(windowMsg(3, t(21), t(28)));
  for (int j : {21, 22, 24, 23, 25, 26, 27, 28}) msgs.push_back(scanMsg(j));
  feed(msgs, &node);

  EXPECT_EQ(missing_per_sweep, (std::vector<int>{3, 0, 1}));
  EXPECT_EQ(node.counter("sweeps"), 3);
  EXPECT_EQ(node.counter("sweeps_incomplete"), 2);
  EXPECT_EQ(node.counter("scans_missing"), 4);
  EXPECT_EQ(node.counter("windows_missing"), 1);
  EXPECT_EQ(node.counter("dropped"), 1);  // scan 23
}

// A lidar that restarts counts from 0 again: no gap; nor does a seq far ahead overflow.
TEST_F(AssemblerNodeTest, SeqRestartIsNoGapAndAWildSeqIsBounded) {
  AssemblerNode node(rig_);
  std::vector<Message> msgs;
  msgs.push_back(windowMsg(0, 1000000, 1000000 + 25000 * 10));
  for (int j = 0; j < 5; ++j) msgs.push_back(scanMsg(j));
  for (int j = 5; j <= 10; ++j) {
    Message m = scanMsg(j);
    lidar_scan_t s;
    ASSERT_TRUE(decodeMessage(m, &s));
    s.seq = j == 5 ? 0 : j == 7 ? std::numeric_limits<int64_t>::max() : j - 5;
    msgs.push_back(encode(channels::kLidarScan, m.utime, s));
  }
  feed(msgs, &node);
  EXPECT_EQ(node.counter("sweeps"), 1);
  // 5 -> seq 0 (restart), 6 -> 1, 7 -> max: the gap holds at most one scan per microsecond
  // between its neighbours (25 ms apart), all inside the window.
  EXPECT_EQ(node.counter("scans_missing"), 25000);
  EXPECT_EQ(node.counter("sweeps_incomplete"), 1);
}

// Without windows the assembler keeps max_pending_scans scans; the gaps among scans it has
// evicted go with them (counted as scans_evicted, not as missing in a later sweep).
TEST_F(AssemblerNodeTest, GapsAmongEvictedScansAreForgotten) {
  rig_.assembler.max_pending_scans = 5;
  AssemblerNode node(rig_);
  std::vector<Message> msgs;
  for (int j = 0; j <= 20; ++j) {
    if (j != 3 && j != 7 && j != 18) msgs.push_back(scanMsg(j));
  }
  msgs.push_back(windowMsg(0, 1000000, 1000000 + 25000 * 20));
  feed(msgs, &node);
  EXPECT_EQ(node.counter("sweeps"), 1);
  EXPECT_GT(node.counter("scans_evicted"), 0);
  EXPECT_EQ(node.counter("scans_missing"), 1);  // 18, among the pending scans
}

}  // namespace
}  // namespace sweepmap
