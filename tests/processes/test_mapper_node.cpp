#include <gtest/gtest.h>

#include <filesystem>

#include "mapping/occupancy_map.hpp"
#include "processes/channels.hpp"
#include "processes/mapper_node.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/map_save_t.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "sweepmap/sweep_status_t.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

template <class T>
Message encode(const std::string& ch, const T& msg) {
  Outbox o;
  o.publish(ch, 0, msg);
  return o.take().front();
}

// A wall of points at x = 2 m split into `count` chunks.
std::vector<Message> wallChunks(int64_t sweep, int count) {
  std::vector<Message> out;
  for (int c = 0; c < count; ++c) {
    cloud_chunk_t m{};
    m.utime = 1000000 * (sweep + 1);  // window start
    m.sweep_id = sweep;
    m.chunk_index = c;
    m.chunk_count = count;
    m.total_points = 100 * count;
    m.frame = "O";
    m.corrected = true;
    for (int i = 0; i < 100; ++i) {
      m.xyz_m.push_back({2.0f, -1.0f + 0.02f * i, 0.2f * c});
    }
    m.npoints = 100;
    out.push_back(encode(channels::kSweepCloud, m));
  }
  return out;
}

std::vector<map_stats_t> deliver(MapperNode& node, const std::vector<Message>& msgs) {
  std::vector<map_stats_t> stats;
  for (const auto& m : msgs) {
    Outbox out;
    node.receive(m, out);
    for (const auto& o : out.take()) {
      map_stats_t s;
      if (o.channel == channels::kMapStats && decodeMessage(o, &s)) stats.push_back(s);
    }
  }
  return stats;
}

TEST(MapperNode, InsertsOnStatusAndCountsMissingChunks) {
  MapperConfig c;
  MapperNode node(c, "");
  auto msgs = wallChunks(0, 3);
  msgs.erase(msgs.begin() + 1);  // chunk 1 lost
  sweep_status_t st{};
  st.utime = 1000000;
  st.sweep_id = 0;
  msgs.push_back(encode(channels::kSweepStatus, st));
  const auto stats = deliver(node, msgs);
  ASSERT_EQ(stats.size(), 1u);
  EXPECT_EQ(stats[0].sweeps_inserted, 1);
  EXPECT_EQ(stats[0].incomplete_sweeps, 1);
  EXPECT_GT(stats[0].occupied_voxels, 0);
  EXPECT_TRUE(node.map().occupiedAt({2.0, 0.0, 0.0}));
  EXPECT_FALSE(node.map().occupiedAt({2.0, 0.0, 0.2}));  // the lost chunk's points
}

TEST(MapperNode, NewerSweepFlushesOlderWhenStatusLost) {
  MapperConfig c;
  MapperNode node(c, "");
  auto msgs = wallChunks(0, 2);
  const auto next = wallChunks(1, 1);
  msgs.insert(msgs.end(), next.begin(), next.end());
  EXPECT_EQ(deliver(node, msgs).size(), 1u);
  EXPECT_EQ(node.counter("sweeps"), 1);
}

TEST(MapperNode, BadChunksRejectedAndSaveIsAtomic) {
  const fs::path dir = fs::temp_directory_path() / "sweepmap_mapper_node_test";
  fs::create_directories(dir);
  MapperConfig c;
  MapperNode node(c, (dir / "default.bt").string());
  cloud_chunk_t bad{};
  bad.chunk_index = 5;
  bad.chunk_count = 2;
  std::vector<Message> msgs = {encode(channels::kSweepCloud, bad),
                               Message{0, channels::kSweepCloud, {9, 9, 9}}};
  auto good = wallChunks(0, 1);
  msgs.insert(msgs.end(), good.begin(), good.end());
  map_save_t save{};
  save.path = (dir / "asked.bt").string();
  msgs.push_back(encode(channels::kMapSave, save));
  deliver(node, msgs);
  EXPECT_EQ(node.counter("invalid"), 2);
  EXPECT_TRUE(fs::exists(dir / "asked.bt"));
  EXPECT_FALSE(fs::exists(dir / "asked.bt.tmp"));
  Outbox out;
  node.finish(0, out);
  EXPECT_TRUE(fs::exists(dir / "default.bt"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sweepmap
