// ViewModel: the point budget thins the oldest sweep first and the pages' arithmetic (a
// ClientQueue's count) follows it; voxels are counted once; bad messages are refused. ClientQueue:
// bulk frames are dropped oldest first and counted, latest frames replace, control frames pass.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <set>
#include <stdexcept>

#include "processes/channels.hpp"
#include "processes/message_codec.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/map_update_t.hpp"
#include "tools/view/client_queue.hpp"
#include "tools/view/view_model.hpp"

namespace sweepmap {
namespace {

// One chunk of `n` points on a line along x, 0.1 m apart; with intensity, point i's is 1000 + i.
Message chunk(int64_t sweep, int index, int count, int n, bool intensity = false) {
  cloud_chunk_t c{};
  c.utime = 1000 * sweep;
  c.sweep_id = sweep;
  c.chunk_index = index;
  c.chunk_count = count;
  c.total_points = n * count;
  c.frame = "O";
  c.npoints = n;
  for (int i = 0; i < n; ++i) c.xyz_m.push_back({0.1f * float(i + index * n), 0.0f, 0.0f});
  for (int i = 0; intensity && i < n; ++i) c.intensities.push_back(1000.0f + float(i));
  c.nintensities = static_cast<int32_t>(c.intensities.size());
  return Message{c.utime, channels::kSweepCloud, encodeMessage(c)};
}

struct Recorder {
  std::vector<ViewFrame> frames;
  ClientQueue page{1u << 30};
  ViewModel::Sink sink() {
    return [this](const ViewFrame& f) {
      frames.push_back(f);
      page.push(f);
    };
  }
  void drain() {
    while (page.pop()) {
    }
  }
};

TEST(ViewModel, BudgetThinsTheOldestSweepFirstAndThePageCountFollows) {
  Recorder r;
  ViewModelOptions o;
  o.point_budget = 1500;
  ViewModel m(o, r.sink());
  m.add(chunk(0, 0, 2, 501), 0);
  m.add(chunk(0, 1, 2, 501), 0);
  EXPECT_EQ(m.pointsOnScreen(), 1002u);
  m.add(chunk(1, 0, 1, 700), 0);  // 1702 > 1500: sweep 0 loses every second point
  EXPECT_EQ(m.pointsOnScreen(), 251u + 251u + 700u);
  EXPECT_EQ(m.counters().thinned, 1);
  r.drain();
  EXPECT_EQ(r.page.counters().points_drawn, static_cast<int64_t>(m.pointsOnScreen()));
  // A late chunk of the thinned sweep comes thinned.
  m.add(chunk(0, 2, 3, 101), 0);
  EXPECT_EQ(r.frames.back().points, 51u);
  r.drain();
  EXPECT_EQ(r.page.counters().points_drawn, static_cast<int64_t>(m.pointsOnScreen()));
}

// A cloud frame's flags and trailing intensities (view_model.hpp's layout), thinned with their
// points; a chunk without intensities has neither.
std::vector<float> frameIntensities(const ViewFrame& f) {
  const std::string& d = *f.data;
  uint32_t n = 0, flags = 0;
  std::memcpy(&n, &d[4], 4);
  std::memcpy(&flags, &d[44], 4);
  if (flags != kCloudHasIntensity) {
    EXPECT_EQ(d.size(), 48u + 12u * n);
    return {};
  }
  EXPECT_EQ(d.size(), 48u + 16u * n);
  std::vector<float> out(n);
  std::memcpy(out.data(), &d[48 + 12 * size_t{n}], 4 * size_t{n});
  return out;
}

const ViewFrame& lastCloud(const std::vector<ViewFrame>& frames) {
  for (auto it = frames.rbegin(); it != frames.rend(); ++it) {
    if (it->effect == ViewFrame::kAddPoints) return *it;
  }
  throw std::runtime_error("no cloud frame");
}

TEST(ViewModel, CloudFramesCarryIntensityThinnedWithTheirPoints) {
  Recorder r;
  ViewModelOptions o;
  o.point_budget = 7;
  ViewModel m(o, r.sink());
  m.add(chunk(0, 0, 2, 5, true), 0);
  EXPECT_EQ(frameIntensities(lastCloud(r.frames)),
            (std::vector<float>{1000, 1001, 1002, 1003, 1004}));
  m.add(chunk(1, 0, 1, 3, false), 0);  // 8 > 7: sweep 0 thinned to every second point
  EXPECT_EQ(m.counters().thinned, 1);
  EXPECT_TRUE(frameIntensities(lastCloud(r.frames)).empty());
  m.add(chunk(0, 1, 2, 5, true), 0);  // a late chunk of the thinned sweep comes thinned
  EXPECT_EQ(frameIntensities(lastCloud(r.frames)), (std::vector<float>{1000, 1002, 1004}));
  EXPECT_EQ(m.counters().thinned, 2);  // 9 > 7: sweep 0 thinned again, 2 + 2 points
  bool found = false;                  // a new page gets sweep 0's first chunk as thinned twice
  for (const ViewFrame& f : m.snapshot()) {
    if (f.effect == ViewFrame::kAddPoints && f.sweep == 0 && !found) {
      EXPECT_EQ(frameIntensities(f), (std::vector<float>{1000, 1004}));
      found = true;
    }
  }
  EXPECT_TRUE(found);
}

TEST(ViewModel, SweepsPastTheLastThinningAreRemovedOldestFirst) {
  Recorder r;
  ViewModelOptions o;
  o.point_budget = 1000;
  ViewModel m(o, r.sink());
  // 100 sweeps at 1/64 still hold 1600 points: the oldest go.
  for (int s = 0; s < 100; ++s) m.add(chunk(s, 0, 1, 990), 0);
  EXPECT_LE(m.pointsOnScreen(), 1000u);
  EXPECT_GT(m.counters().removed_sweeps, 0);
  r.drain();
  EXPECT_EQ(r.page.counters().points_drawn, static_cast<int64_t>(m.pointsOnScreen()));
}

TEST(ViewModel, VoxelsAreSentOnceAndMalformedChunksAreCounted) {
  Recorder r;
  ViewModel m(ViewModelOptions{}, r.sink());
  m.add(chunk(0, 0, 1, 10), 0);  // 10 points 0.1 m apart at 0.05 m: 10 voxels
  m.add(chunk(1, 0, 1, 10), 0);  // the same points again: no new voxel
  EXPECT_EQ(m.voxels(), 10u);
  Message bad = chunk(2, 0, 1, 10);
  bad.data.resize(bad.data.size() - 5);
  m.add(bad, 0);
  EXPECT_EQ(m.counters().malformed, 1);
  EXPECT_EQ(m.counters().chunks, 2);
}

Message mapUpdate(int64_t seq, std::vector<std::vector<int32_t>> occupied,
                  std::vector<std::vector<int32_t>> freed, int64_t total, bool full = false,
                  int chunk_index = 0, int chunk_count = 1) {
  map_update_t u{};
  u.seq = seq;
  u.full = full;
  u.chunk_index = chunk_index;
  u.chunk_count = chunk_count;
  u.resolution_m = 0.1;
  u.total_occupied = u.noccupied = static_cast<int32_t>(occupied.size());
  u.total_freed = u.nfreed = static_cast<int32_t>(freed.size());
  u.occupied = std::move(occupied);
  u.freed = std::move(freed);
  u.occupied_voxels = total;
  return Message{0, channels::kMapUpdate, encodeMessage(u)};
}

// The voxels a page holds after the voxel frames and "voxels" controls so far (view.js's rule).
std::set<std::array<int32_t, 3>> pageVoxels(const std::vector<ViewFrame>& frames) {
  std::set<std::array<int32_t, 3>> out;
  for (const ViewFrame& f : frames) {
    const std::string& d = *f.data;
    if (!f.binary) {
      if (d.find("\"type\":\"voxels\"") != std::string::npos) out.clear();
      continue;
    }
    if (d[0] != 2) continue;
    uint32_t n = 0, flags = 0;
    std::memcpy(&n, &d[4], 4);
    std::memcpy(&flags, &d[12], 4);
    EXPECT_EQ(d.size(), 16u + 12u * n);
    for (uint32_t k = 0; k < n; ++k) {
      std::array<int32_t, 3> v;
      std::memcpy(v.data(), &d[16 + 12 * k], 12);
      flags& kVoxelsRemoved ? static_cast<void>(out.erase(v)) : static_cast<void>(out.insert(v));
    }
  }
  return out;
}

// MAP_UPDATE replaces the cloud-derived voxels, adds and removes; a new page's snapshot holds
// the same set; bad updates are counted and change nothing; a seq jump is counted.
TEST(ViewModel, MapUpdatesDriveTheVoxels) {
  Recorder r;
  ViewModel m(ViewModelOptions{}, r.sink());
  m.add(chunk(0, 0, 1, 10), 0);  // the fallback: 10 cloud-derived voxels
  EXPECT_EQ(m.voxels(), 10u);
  EXPECT_FALSE(m.voxelsFromMapper());
  m.add(mapUpdate(1, {{1, 2, 3}, {4, 5, 6}, {-7, 8, 9}}, {}, 3), 0);
  m.add(mapUpdate(2, {{0, 0, 0}}, {{4, 5, 6}}, 3), 0);
  m.add(chunk(1, 0, 1, 10), 0);  // clouds no longer make voxels
  EXPECT_TRUE(m.voxelsFromMapper());
  const std::set<std::array<int32_t, 3>> expected = {{0, 0, 0}, {1, 2, 3}, {-7, 8, 9}};
  EXPECT_EQ(m.voxels(), 3u);
  EXPECT_EQ(pageVoxels(r.frames), expected);
  EXPECT_EQ(pageVoxels(m.snapshot()), expected);
  EXPECT_EQ(m.counters().mapper_occupied_voxels, 3);
  Message spoilt = mapUpdate(3, {{1, 1, 1}}, {}, 4);
  spoilt.data.resize(spoilt.data.size() - 3);
  m.add(spoilt, 0);
  m.add(mapUpdate(3, {{1, 1, 1}}, {}, -4), 0);  // decodes, but fails validateMapUpdate
  EXPECT_EQ(m.counters().map_updates_invalid, 2);
  EXPECT_EQ(m.counters().malformed, 2);
  EXPECT_EQ(m.voxels(), 3u);
  m.add(mapUpdate(5, {}, {{0, 0, 0}}, 2), 0);  // 3 and 4 lost
  EXPECT_EQ(m.counters().map_update_gaps, 2);
  EXPECT_EQ(m.voxels(), 2u);
  m.add(mapUpdate(1, {{9, 9, 9}}, {}, 1), 0);  // the mapper started again
  EXPECT_EQ(pageVoxels(r.frames), (std::set<std::array<int32_t, 3>>{{9, 9, 9}}));
  // A full update in two chunks: what it does not list goes once both came; with one lost,
  // nothing goes and a gap is counted.
  m.add(mapUpdate(2, {{1, 1, 1}}, {}, 2, true, 0, 2), 0);
  m.add(mapUpdate(2, {{2, 2, 2}}, {}, 2, true, 1, 2), 0);
  const std::set<std::array<int32_t, 3>> full = {{1, 1, 1}, {2, 2, 2}};
  EXPECT_EQ(pageVoxels(r.frames), full);
  EXPECT_EQ(pageVoxels(m.snapshot()), full);
  const int64_t gaps = m.counters().map_update_gaps;
  m.add(mapUpdate(3, {{3, 3, 3}}, {}, 2, true, 1, 2), 0);  // chunk 0 lost
  EXPECT_EQ(m.counters().map_update_gaps, gaps + 1);
  EXPECT_EQ(m.voxels(), 3u);
}

// A page whose queue dropped a voxel frame is marked stale; the voxel snapshot sent then
// (what the server does, ViewServer's on_voxels_stale) gives it the view's set again, after
// the frames it still had queued.
TEST(ViewModel, APageThatLostAVoxelFrameGetsTheWholeSetAgain) {
  ClientQueue page(100);  // smaller than one voxel frame of 10 keys (136 bytes)
  ViewModel m(ViewModelOptions{}, [&](const ViewFrame& f) { page.push(f); });
  std::vector<ViewFrame> drawn;
  auto drain = [&] {
    while (auto f = page.pop()) drawn.push_back(*f);
  };
  m.add(mapUpdate(1, {{1, 1, 1}, {2, 2, 2}}, {}, 2), 0);
  drain();
  EXPECT_FALSE(page.voxelsStale());
  std::vector<std::vector<int32_t>> many;
  for (int i = 0; i < 10; ++i) many.push_back({i, 0, 7});
  m.add(mapUpdate(2, many, {{1, 1, 1}}, 11), 0);  // the additions do not fit: dropped
  EXPECT_FALSE(page.takeVoxelsStale());           // not while the removal is still queued
  drain();
  EXPECT_TRUE(page.voxelsStale());
  EXPECT_NE(pageVoxels(drawn).size(), m.voxels());
  ASSERT_TRUE(page.takeVoxelsStale());
  EXPECT_FALSE(page.takeVoxelsStale());
  EXPECT_EQ(page.counters().voxel_resyncs, 1);
  ClientQueue roomy(1u << 20);
  for (const ViewFrame& f : m.voxelSnapshot()) roomy.push(f);
  while (auto f = roomy.pop()) drawn.push_back(*f);
  EXPECT_EQ(pageVoxels(drawn).size(), 11u);
  EXPECT_EQ(pageVoxels(drawn), pageVoxels(m.snapshot()));
  // Other bulk frames lost do not make the voxels stale.
  ClientQueue q(10);
  ViewFrame cloud;
  cloud.kind = ViewFrame::kBulk;
  cloud.data = std::make_shared<const std::string>(50, 'x');
  q.push(cloud);
  EXPECT_EQ(q.counters().frames_dropped, 1);
  EXPECT_FALSE(q.voxelsStale());
}

ViewFrame frame(ViewFrame::Kind kind, size_t bytes, const std::string& key = "") {
  ViewFrame f;
  f.kind = kind;
  f.key = key;
  f.data = std::make_shared<const std::string>(bytes, 'x');
  return f;
}

TEST(ClientQueue, DropsOldestBulkReplacesLatestKeepsControl) {
  ClientQueue q(1000);
  q.push(frame(ViewFrame::kBulk, 400));
  q.push(frame(ViewFrame::kLatest, 50, "pose"));
  q.push(frame(ViewFrame::kBulk, 400));
  q.push(frame(ViewFrame::kLatest, 60, "pose"));  // replaces the first pose
  q.push(frame(ViewFrame::kControl, 10));
  q.push(frame(ViewFrame::kBulk, 400));  // no room: the oldest bulk frame goes
  const ClientCounters c = q.counters();
  EXPECT_EQ(c.frames_dropped, 1);
  EXPECT_EQ(c.replaced, 1);
  EXPECT_EQ(c.queued_frames, 4u);
  EXPECT_LE(c.queued_bytes, 1000u);
  EXPECT_EQ(q.pop()->kind, ViewFrame::kLatest);  // the bulk frame before it was dropped
}

}  // namespace
}  // namespace sweepmap
