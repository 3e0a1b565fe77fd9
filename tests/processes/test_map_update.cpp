// MAP_UPDATE: the mapper's stream of voxel changes rebuilds its OctoMap's occupied voxels, its
// chunks stay within one datagram, and malformed updates are refused with a reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "mapping/occupancy_map.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/mapper_node.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "sweepmap/map_update_t.hpp"
#include "sweepmap/sweep_status_t.hpp"
#include "tests/processes/node_test_util.hpp"

namespace sweepmap {
namespace {

using Voxel = std::array<int32_t, 3>;

using test::encode;

// One sweep (one chunk and its status) from the origin: a wall at x = `wall_x` (y, z in
// [-2, 2) every 4 cm: 80 x 80 voxels, more than one MAP_UPDATE chunk), and, when `cube`, a solid
// 0.2 m cube at [1.0, 1.2)^3 (whole voxels: OctoMap prunes it into blocks).
std::vector<Message> sweep(int64_t id, float wall_x, bool cube) {
  cloud_chunk_t m{};
  m.utime = 1000000 * (id + 1);
  m.sweep_id = id;
  m.chunk_count = 1;
  m.frame = "O";
  for (int y = 0; y < 100; ++y) {
    for (int z = 0; z < 100; ++z)
      m.xyz_m.push_back({wall_x, -1.99f + 0.04f * y, -1.99f + 0.04f * z});
  }
  for (int i = 0; cube && i < 20 * 20 * 20; ++i) {
    m.xyz_m.push_back(
        {1.005f + 0.01f * (i % 20), 1.005f + 0.01f * (i / 20 % 20), 1.005f + 0.01f * (i / 400)});
  }
  m.npoints = m.total_points = static_cast<int32_t>(m.xyz_m.size());
  sweep_status_t st{};
  st.utime = m.utime;
  st.sweep_id = id;
  st.chunk_count = 1;
  return {encode(channels::kSweepCloud, m), encode(channels::kSweepStatus, st)};
}

// What a receiver keeps: the occupied set, built from the updates as they come.
struct Receiver {
  std::set<Voxel> occupied;
  int64_t last_seq = 0, freed = 0, chunks = 0, last_total = -1;
  size_t max_chunk_voxels = 0;
  int64_t join_seq = 1;  // updates before this one are not seen (a viewer started late)
  bool synced = true;    // false until a full update when join_seq > 1
  void apply(const Message& m) {
    map_update_t u;
    ASSERT_TRUE(decodeMessage(m, &u));
    ASSERT_EQ(validateMapUpdate(u), "");
    if (u.seq < join_seq) return;
    EXPECT_TRUE(u.seq == last_seq || u.seq == last_seq + 1 || last_seq == 0) << u.seq;
    EXPECT_EQ(u.full, (u.seq - 1) % MapperNode::kFullUpdateEvery == 0) << u.seq;
    last_seq = u.seq;
    ++chunks;
    max_chunk_voxels = std::max(max_chunk_voxels, u.occupied.size() + u.freed.size());
    if (u.full && u.chunk_index == 0) {
      occupied.clear();
      synced = true;
    }
    if (!synced) return;
    for (const auto& v : u.occupied) EXPECT_TRUE(occupied.insert({v[0], v[1], v[2]}).second);
    for (const auto& v : u.freed) EXPECT_EQ(occupied.erase({v[0], v[1], v[2]}), 1u);
    freed += u.nfreed;
    last_total = u.occupied_voxels;
  }
};

// Feeds `msgs`; every MAP_UPDATE goes to `rx`, and each MAP_STATS is checked against the set
// rebuilt so far: the updates of a map update come before its statistics.
void deliver(MapperNode& node, const std::vector<Message>& msgs, Receiver* rx) {
  for (const Message& m : msgs) {
    Outbox out;
    node.receive(m, out);
    for (const Message& o : out.take()) {
      if (o.channel == channels::kMapUpdate) rx->apply(o);
      map_stats_t s;
      if (o.channel == channels::kMapStats && rx->synced && decodeMessage(o, &s)) {
        EXPECT_EQ(s.occupied_voxels, static_cast<int64_t>(rx->occupied.size()));
        EXPECT_EQ(rx->last_total, s.occupied_voxels);
      }
    }
  }
}

std::vector<Voxel> asVector(const std::set<Voxel>& s) { return {s.begin(), s.end()}; }

// A wall seen once, then a wall behind it seen through it: the first wall's voxels are freed by
// the rays that pass them. After every sweep the set rebuilt from MAP_UPDATE is the tree's
// occupied leaves at full depth (pruned blocks of the cube expanded), and MAP_STATS' count.
TEST(MapUpdate, StreamRebuildsTheOccupiedVoxelsIncludingFreedOnes) {
  MapperConfig c;
  MapperNode node(c, "");
  Receiver rx;
  deliver(node, sweep(0, 2.0f, true), &rx);
  EXPECT_EQ(asVector(rx.occupied), node.map().occupiedVoxels());
  EXPECT_TRUE(rx.occupied.count({40, 0, 0}));  // x = 2.0 m
  for (int64_t id = 1; id <= 8; ++id) {
    deliver(node, sweep(id, 3.0f, false), &rx);
    EXPECT_EQ(asVector(rx.occupied), node.map().occupiedVoxels()) << "after sweep " << id;
  }
  EXPECT_EQ(rx.last_seq, 9);
  EXPECT_GT(rx.freed, 1000) << "the rays through the first wall freed too little of it";
  EXPECT_FALSE(rx.occupied.count({40, 0, 0}));
  EXPECT_TRUE(rx.occupied.count({60, 0, 0}));
  EXPECT_TRUE(rx.occupied.count({21, 21, 21}));  // inside the cube, pruned in the tree
  EXPECT_EQ(static_cast<int64_t>(rx.occupied.size()), node.map().stats().occupied_voxels);
  EXPECT_LE(rx.max_chunk_voxels, static_cast<size_t>(kMapUpdateChunkVoxels));
  EXPECT_GT(rx.chunks, rx.last_seq) << "the first update (6464 voxels) is one chunk";
}

// OccupancyMap's changes alone, over both ways of insertion (its own discretized one, and
// OctoMap's insertPointCloud, whose updates the tracker does not see) and a map that had voxels
// before tracking began: applied in turn, they give occupiedVoxels() after every insertion.
TEST(MapUpdate, ChangesFollowEveryInsertModeFromAnyStart) {
  OccupancyMap map(MapperConfig{});
  std::vector<Eigen::Vector3f> wall;
  for (int i = 0; i < 400; ++i) wall.emplace_back(1.5f, -1.0f + 0.005f * i, 0.1f * (i % 7));
  map.insertCloud(wall, Eigen::Vector3f::Zero());
  map.trackChanges();
  std::set<Voxel> rebuilt;
  for (const Voxel& v : map.occupiedVoxels()) rebuilt.insert(v);
  const InsertMode modes[] = {InsertMode::kDiscretized, InsertMode::kEveryRay,
                              InsertMode::kOctomapDiscretized};
  int64_t freed = 0;
  for (int k = 0; k < 9; ++k) {
    std::vector<Eigen::Vector3f> far;
    for (const auto& p : wall) far.emplace_back(p.x() + 0.5f + 0.1f * (k % 3), p.y(), p.z());
    map.insertCloud(far, Eigen::Vector3f(0.0f, 0.01f * k, 0.0f), modes[k % 3]);
    const VoxelChanges c = map.takeChanges();
    EXPECT_TRUE(std::is_sorted(c.occupied.begin(), c.occupied.end()));
    EXPECT_TRUE(std::is_sorted(c.freed.begin(), c.freed.end()));
    for (const Voxel& v : c.occupied) EXPECT_TRUE(rebuilt.insert(v).second);
    for (const Voxel& v : c.freed) EXPECT_EQ(rebuilt.erase(v), 1u);
    freed += static_cast<int64_t>(c.freed.size());
    EXPECT_EQ(asVector(rebuilt), map.occupiedVoxels()) << "after insertion " << k;
    EXPECT_EQ(map.trackedVoxels(), map.occupiedVoxels()) << "after insertion " << k;
  }
  EXPECT_GT(freed, 0);
  EXPECT_TRUE(map.takeChanges().occupied.empty());
}

// A viewer that starts after the mapper has the mapper's voxels from the next full update on.
TEST(MapUpdate, ALateViewerCatchesUpAtTheNextFullUpdate) {
  MapperNode node(MapperConfig{}, "");
  Receiver rx;
  rx.join_seq = 4;
  rx.synced = false;
  for (int64_t id = 0; id <= MapperNode::kFullUpdateEvery; ++id) {
    deliver(node, sweep(id, id % 4 ? 3.0f : 2.0f, id == 2), &rx);
  }
  EXPECT_EQ(rx.last_seq, MapperNode::kFullUpdateEvery + 1);
  EXPECT_TRUE(rx.synced);
  EXPECT_EQ(asVector(rx.occupied), node.map().occupiedVoxels());
}

// A mobile rig's batches (mapper.batch_s): one update per batch, flushed at finish().
TEST(MapUpdate, BatchesPublishOneUpdateEach) {
  MapperConfig c;
  c.batch_s = 100.0;
  MapperNode node(c, "");
  Receiver rx;
  deliver(node, sweep(0, 2.0f, false), &rx);
  deliver(node, sweep(1, 3.0f, true), &rx);
  EXPECT_EQ(rx.last_seq, 0);  // still in the batch
  Outbox out;
  node.finish(0, out);
  for (const Message& o : out.take()) {
    if (o.channel == channels::kMapUpdate) rx.apply(o);
  }
  EXPECT_EQ(rx.last_seq, 1);
  EXPECT_EQ(asVector(rx.occupied), node.map().occupiedVoxels());
}

// The same inserts give the same bytes (the tree's hash map of changed keys leaks no order).
TEST(MapUpdate, OutputIsDeterministic) {
  std::vector<std::vector<uint8_t>> runs[2];
  for (auto& run : runs) {
    MapperNode node(MapperConfig{}, "");
    for (int64_t id = 0; id < 3; ++id) {
      for (const Message& m : sweep(id, id ? 3.0f : 2.0f, id == 1)) {
        Outbox out;
        node.receive(m, out);
        for (const Message& o : out.take()) {
          if (o.channel == channels::kMapUpdate) run.push_back(o.data);
        }
      }
    }
  }
  EXPECT_EQ(runs[0], runs[1]);
  EXPECT_GE(runs[0].size(), 3u);
}

TEST(MapUpdate, ChunksKeepOrderAndTotals) {
  std::vector<Voxel> occupied, freed;
  for (int i = 0; i < 9; ++i) occupied.push_back({i, 0, 0});
  for (int i = 0; i < 5; ++i) freed.push_back({0, i, 0});
  map_update_t header{};
  header.seq = 3;
  header.resolution_m = 0.05;
  const auto chunks = toMapUpdates(occupied, freed, header, 4);
  ASSERT_EQ(chunks.size(), 4u);
  std::vector<Voxel> got_occupied, got_freed;
  for (size_t c = 0; c < chunks.size(); ++c) {
    EXPECT_EQ(validateMapUpdate(chunks[c]), "");
    EXPECT_EQ(chunks[c].chunk_index, static_cast<int>(c));
    EXPECT_EQ(chunks[c].chunk_count, 4);
    EXPECT_EQ(chunks[c].total_occupied, 9);
    EXPECT_EQ(chunks[c].total_freed, 5);
    EXPECT_LE(chunks[c].noccupied + chunks[c].nfreed, 4);
    for (const auto& v : chunks[c].occupied) got_occupied.push_back({v[0], v[1], v[2]});
    for (const auto& v : chunks[c].freed) got_freed.push_back({v[0], v[1], v[2]});
  }
  EXPECT_EQ(got_occupied, occupied);
  EXPECT_EQ(got_freed, freed);
  const auto empty = toMapUpdates({}, {}, header);
  ASSERT_EQ(empty.size(), 1u);
  EXPECT_EQ(empty[0].chunk_count, 1);
  EXPECT_EQ(validateMapUpdate(empty[0]), "");
  // A full chunk is one UDP datagram.
  std::vector<Voxel> many(kMapUpdateChunkVoxels, Voxel{-32768, 0, 32767});
  const auto full = toMapUpdates(many, {}, header);
  ASSERT_EQ(full.size(), 1u);
  EXPECT_LT(encodeMessage(full[0]).size(), 65507u);
}

map_update_t validUpdate() {
  map_update_t m{};
  m.seq = 1;
  m.chunk_count = 1;
  m.resolution_m = 0.05;
  m.total_occupied = m.noccupied = 2;
  m.occupied = {{1, 2, 3}, {4, 5, 6}};
  m.total_freed = m.nfreed = 1;
  m.freed = {{7, 8, 9}};
  m.occupied_voxels = 2;
  return m;
}

// Each field made wrong in turn: the reason names it.
TEST(MapUpdate, ValidationRefusesEachBadField) {
  ASSERT_EQ(validateMapUpdate(validUpdate()), "");
  const std::vector<std::pair<std::string, std::function<void(map_update_t&)>>> cases = {
      {"seq", [](map_update_t& m) { m.seq = 0; }},
      {"chunk index", [](map_update_t& m) { m.chunk_index = 1; }},
      {"chunk index", [](map_update_t& m) { m.chunk_count = 0; }},
      {"chunk index", [](map_update_t& m) { m.chunk_index = -1; }},
      {"do not match", [](map_update_t& m) { m.noccupied = 3; }},
      {"do not match", [](map_update_t& m) { m.nfreed = -1; }},
      {"more voxels than its update", [](map_update_t& m) { m.total_occupied = 1; }},
      {"more voxels than its update", [](map_update_t& m) { m.total_freed = 0; }},
      {"resolution", [](map_update_t& m) { m.resolution_m = 0.0; }},
      {"resolution", [](map_update_t& m) { m.resolution_m = NAN; }},
      {"resolution", [](map_update_t& m) { m.resolution_m = INFINITY; }},
      {"occupied_voxels", [](map_update_t& m) { m.occupied_voxels = -1; }},
      {"outside", [](map_update_t& m) { m.occupied[1][2] = 40000; }},
      {"outside", [](map_update_t& m) { m.freed[0][0] = -32769; }},
      {"not 3 indices", [](map_update_t& m) { m.freed[0].pop_back(); }},
      {"full update frees", [](map_update_t& m) { m.full = true; }},
  };
  for (const auto& [what, spoil] : cases) {
    map_update_t m = validUpdate();
    spoil(m);
    const std::string why = validateMapUpdate(m);
    EXPECT_NE(why.find(what), std::string::npos) << what << ": '" << why << "'";
  }
  map_update_t big = validUpdate();
  big.occupied.assign(kMapUpdateChunkVoxels + 1, {0, 0, 0});
  big.noccupied = big.total_occupied = kMapUpdateChunkVoxels + 1;
  EXPECT_NE(validateMapUpdate(big).find("voxels in one chunk"), std::string::npos);
}

// Random bytes over an encoded update: decoding refuses or validation judges it; nothing throws
// or crashes, and an unchanged message stays valid.
TEST(MapUpdate, CorruptedBytesAreRefusedOrJudged) {
  const std::vector<uint8_t> good = encodeMessage(validUpdate());
  std::mt19937 rng(7);
  int refused = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<uint8_t> bytes = good;
    const int flips = 1 + trial % 4;
    for (int k = 0; k < flips; ++k) bytes[rng() % bytes.size()] = static_cast<uint8_t>(rng());
    if (trial % 5 == 0) bytes.resize(rng() % bytes.size());
    map_update_t m;
    if (!decodeMessage(bytes.data(), bytes.size(), &m) || !validateMapUpdate(m).empty()) {
      ++refused;
    }
  }
  EXPECT_GT(refused, 400);
  map_update_t m;
  ASSERT_TRUE(decodeMessage(good.data(), good.size(), &m));
  EXPECT_EQ(validateMapUpdate(m), "");
}

}  // namespace
}  // namespace sweepmap
