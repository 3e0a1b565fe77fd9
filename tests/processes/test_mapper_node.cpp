#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "mapping/occupancy_map.hpp"
#include "processes/channels.hpp"
#include "processes/mapper_node.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/map_save_t.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "sweepmap/sweep_status_t.hpp"
#include "tests/processes/node_test_util.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

using test::encode;

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

// --save-every 2: the map file is written after every second sweep, before any MAP_SAVE or
// finish(), so a mapper killed with kill -9 leaves its last saved map behind.
TEST(MapperNode, SavesEveryNSweeps) {
  const fs::path dir = fs::path(SWEEPMAP_BINARY_DIR) / "test_scratch" / "mapper_save_every";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string path = (dir / "map.bt").string();
  MapperNode node(MapperConfig{}, path, 2);
  const auto sweep = [&](int64_t id) {
    auto msgs = wallChunks(id, 2);
    sweep_status_t st{};
    st.utime = 1000000 * (id + 1);
    st.sweep_id = id;
    msgs.push_back(encode(channels::kSweepStatus, st));
    deliver(node, msgs);
  };
  sweep(0);
  EXPECT_FALSE(fs::exists(path));
  sweep(1);
  ASSERT_TRUE(fs::exists(path));
  EXPECT_EQ(node.counter("saves"), 1);
  EXPECT_TRUE(OccupancyMap::loadBinary(path).occupiedAt({2.0, 0.0, 0.0}));
  sweep(2);
  EXPECT_EQ(node.counter("saves"), 1);
  sweep(3);
  EXPECT_EQ(node.counter("saves"), 2);
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

// MAP_SAVE comes from the network: only safe *.bt names, never over a file this mapper did
// not write, one per second of message time, and every refusal counted.
TEST(MapperNode, MapSaveIsARequestNotACommand) {
  const fs::path dir = fs::temp_directory_path() / "sweepmap_mapper_node_save_rules";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "run.lcmlog") << "a log";
  std::ofstream(dir / "other.bt") << "not ours";
  MapperNode node(MapperConfig{}, (dir / "map.bt").string());
  deliver(node, wallChunks(0, 1));
  int64_t t = 10'000'000;
  auto request = [&](const std::string& path, int64_t dt_s = 6) {
    map_save_t m{};
    m.path = path;
    Message msg = encode(channels::kMapSave, m);
    t += dt_s * 1'000'000;
    msg.utime = t;
    deliver(node, {msg});
  };
  for (const std::string& bad :
       std::vector<std::string>{"-rf", "evil\nname.bt", "run.lcmlog", ".hidden.bt", "x.bt\n",
                                std::string(70, 'a') + ".bt", "other.bt"}) {
    request(bad);
  }
  EXPECT_EQ(node.counter("refused_saves"), 7);
  EXPECT_EQ(node.counter("saves"), 0);
  std::ifstream log(dir / "run.lcmlog");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(log), {}), "a log");
  EXPECT_FALSE(fs::exists(dir / "-rf"));
  request("../../elsewhere.bt");  // only the name counts: saved in the mapper's folder
  EXPECT_TRUE(fs::exists(dir / "elsewhere.bt"));
  request("again.bt", 0);  // too soon after the last one
  EXPECT_EQ(node.counter("refused_saves"), 8);
  request("elsewhere.bt");  // its own file again: fine
  request("");              // the configured path
  EXPECT_EQ(node.counter("saves"), 2 + 0 + 1);
  int accepted = 0;
  for (int i = 0; i < 30; ++i) {
    const int64_t before = node.counter("saves");
    request("m" + std::to_string(i) + ".bt");
    accepted += node.counter("saves") > before;
  }
  EXPECT_EQ(accepted,
            static_cast<int>(MapperConfig{}.max_requested_files) - 1);  // elsewhere.bt was one
  fs::remove_all(dir);
}

// Sweeps that never complete (a forged or lost chunk stream) are bounded: the oldest goes into
// the map as it is, counted, and nothing piles up.
// The bound is the config's (mapper.max_pending_sweeps).
void expectPendingSweepsBounded(const MapperConfig& config) {
  MapperNode node(config, "");
  std::vector<Message> msgs;
  for (int k = 0; k < 50; ++k) {
    cloud_chunk_t m{};
    m.utime = 1'000'000 - 1000 * k;  // ever older: no newer sweep flushes them
    m.sweep_id = k;
    m.chunk_index = 0;
    m.chunk_count = 3;  // never completes
    m.xyz_m.push_back({1.0f, 0.0f, 0.0f});
    m.npoints = m.total_points = 1;
    msgs.push_back(encode(channels::kSweepCloud, m));
  }
  deliver(node, msgs);
  EXPECT_EQ(node.counter("pending_evicted"), 50 - config.max_pending_sweeps);
  EXPECT_EQ(node.counter("incomplete_sweeps"), 50 - config.max_pending_sweeps);
}

TEST(MapperNode, PendingSweepsAreBounded) {
  expectPendingSweepsBounded(MapperConfig{});
  MapperConfig two;
  two.max_pending_sweeps = 2;
  expectPendingSweepsBounded(two);
}

// Rig B: one single-chunk world-frame sweep per lidar scan (7 Hz), the sensor moving.
std::vector<Message> worldScans(int count) {
  std::vector<Message> out;
  for (int k = 0; k < count; ++k) {
    cloud_chunk_t m{};
    m.utime = 300000 + 142857 * static_cast<int64_t>(k);
    m.sweep_id = k;
    m.chunk_index = 0;
    m.chunk_count = 1;
    m.frame = "world";
    const float x = 0.03f * static_cast<float>(k);
    m.sensor_origin_m[0] = x;
    m.sensor_origin_m[1] = 0.0;
    m.sensor_origin_m[2] = 0.3;
    for (int i = 0; i < 60; ++i) {
      const float a = static_cast<float>(i) * 0.05f;
      m.xyz_m.push_back({x, 2.0f * std::cos(a), 0.3f + 2.0f * std::sin(a)});
    }
    m.npoints = m.total_points = static_cast<int32_t>(m.xyz_m.size());
    Message msg = encode(channels::kSweepCloud, m);
    msg.utime = m.utime + 150000;
    out.push_back(msg);
  }
  return out;
}

TEST(MapperNode, BatchesByMessageTimeAndBuildsTheSameMap) {
  const fs::path dir = fs::temp_directory_path() / "sweepmap_mapper_node_batch_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  MapperConfig single_config;
  MapperConfig batch_config;
  batch_config.batch_s = 1.0;
  MapperNode single(single_config, (dir / "single.bt").string());
  MapperNode batched(batch_config, (dir / "batched.bt").string());
  auto msgs = worldScans(25);  // 0.3 .. 3.73 s: windows [0,1) [1,2) [2,3) [3,4)
  map_save_t save{};
  save.path = "mid.bt";
  msgs.insert(msgs.begin() + 12, encode(channels::kMapSave, save));
  std::vector<map_stats_t> stats[2];
  for (int n = 0; n < 2; ++n) {
    MapperNode& node = n == 0 ? single : batched;
    stats[n] = deliver(node, msgs);
    // The mid-run save holds the same sweeps either way.
    fs::rename(dir / "mid.bt", dir / (n == 0 ? "single_mid.bt" : "batched_mid.bt"));
    Outbox out;
    node.finish(5000000, out);
    for (const auto& o : out.take()) {
      map_stats_t st;
      if (o.channel == channels::kMapStats && decodeMessage(o, &st)) stats[n].push_back(st);
    }
  }
  ASSERT_EQ(stats[0].size(), 25u);  // one per sweep
  // One per batch: [0, 1) s; [1, 2) s so far, flushed by the mid-run save; the rest of
  // [1, 2) s; [2, 3) s; and at finish [3, 4) s.
  ASSERT_EQ(stats[1].size(), 5u);
  EXPECT_EQ(stats[1].back().sweeps_inserted, 25);
  EXPECT_EQ(stats[0].back().occupied_voxels, stats[1].back().occupied_voxels);
  EXPECT_EQ(stats[0].back().free_voxels, stats[1].back().free_voxels);
  EXPECT_EQ(single.counter("sweeps"), 25);
  EXPECT_EQ(batched.counter("sweeps"), 25);
  const auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  ASSERT_GT(bytes(dir / "single.bt").size(), 100u);
  EXPECT_EQ(bytes(dir / "single.bt"), bytes(dir / "batched.bt"));
  EXPECT_EQ(bytes(dir / "single_mid.bt"), bytes(dir / "batched_mid.bt"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sweepmap
