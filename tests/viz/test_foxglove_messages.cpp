#include <gtest/gtest.h>

#include <cstring>
#include <nlohmann/json.hpp>

#include "processes/channels.hpp"
#include "processes/message_codec.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/map_update_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "viz/foxglove_messages.hpp"

namespace sweepmap::viz {
namespace {

using nlohmann::json;

std::vector<uint8_t> unbase64(const std::string& s) {
  std::vector<uint8_t> out;
  uint32_t v = 0;
  int bits = 0;
  for (char c : s) {
    const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char* at = std::strchr(table, c);
    if (c == '=' || !at) break;
    v = (v << 6) | static_cast<uint32_t>(at - table);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<uint8_t>(v >> bits));
    }
  }
  return out;
}

std::vector<FoxgloveMessage> onTopic(const std::vector<FoxgloveMessage>& all,
                                     const std::string& topic) {
  std::vector<FoxgloveMessage> out;
  for (const auto& m : all) {
    if (m.topic == topic) out.push_back(m);
  }
  return out;
}

cloud_chunk_t chunk(std::vector<std::array<float, 3>> points) {
  cloud_chunk_t c{};
  c.utime = 1500000;
  c.chunk_count = 1;
  c.total_points = static_cast<int32_t>(points.size());
  c.frame = "O";
  c.corrected = true;
  c.phi_offset_rad = 0.1;
  c.npoints = c.total_points;
  for (const auto& p : points) c.xyz_m.push_back({p[0], p[1], p[2]});
  return c;
}

TEST(FoxgloveSchemas, EveryEmittedSchemaIsEmbeddedAsJsonSchema) {
  for (const auto& [topic, schema] : foxgloveTopics()) {
    const FoxgloveSchema* s = foxgloveSchema(schema);
    ASSERT_NE(s, nullptr) << topic;
    EXPECT_EQ(s->encoding, "jsonschema");
    EXPECT_EQ(json::parse(s->data).at("title"), schema);
  }
}

TEST(FoxgloveConverter, CloudChunkBecomesPackedPointCloudWithTheSamePoints) {
  FoxgloveConverter conv(loadRig("rig_a"));
  const auto bytes = encodeMessage(chunk({{1.0f, 2.0f, 3.0f}, {-0.5f, 0.25f, 7.0f}}));
  const auto out = conv.convert(channels::kSweepCloud, bytes.data(), bytes.size(), 42);
  const auto clouds = onTopic(out, "/sweep_cloud");
  ASSERT_EQ(clouds.size(), 1u);
  const json j = json::parse(clouds[0].json);
  EXPECT_EQ(j["frame_id"], "O");
  EXPECT_EQ(j["point_stride"], 12);  // no intensity field: the chunk has none
  EXPECT_EQ(j["fields"].size(), 3u);
  EXPECT_EQ(j["timestamp"]["sec"], 1);
  EXPECT_EQ(j["timestamp"]["nsec"], 500000000);
  const auto data = unbase64(j["data"]);
  ASSERT_EQ(data.size(), 24u);
  float f[6];
  std::memcpy(f, data.data(), 24);
  EXPECT_EQ(f[0], 1.0f);
  EXPECT_EQ(f[4], 0.25f);
  EXPECT_EQ(f[5], 7.0f);
  EXPECT_EQ(clouds[0].log_time_ns, 42);
  // The rig's frames come with the first message; the map with finish().
  EXPECT_FALSE(onTopic(out, "/tf").empty());
  const auto map = conv.finish(43);
  ASSERT_EQ(map.size(), 1u);
  EXPECT_EQ(unbase64(json::parse(map[0].json)["data"]).size(), 24u);  // two voxels
  EXPECT_TRUE(conv.finish(44).empty());                               // unchanged
}

// /map from MAP_UPDATE: the first update replaces the cloud-derived voxels and goes out at once
// (its last chunk); freed voxels leave; an invalid update is counted and changes nothing.
TEST(FoxgloveConverter, MapFollowsTheMappersUpdates) {
  FoxgloveConverter conv(loadRig("rig_a"));
  const auto cloud = encodeMessage(chunk({{1.0f, 2.0f, 3.0f}, {-0.5f, 0.25f, 7.0f}}));
  conv.convert(channels::kSweepCloud, cloud.data(), cloud.size(), 1);
  map_update_t u{};
  u.seq = 1;
  u.chunk_count = 1;
  u.resolution_m = 0.5;
  u.occupied = {{0, 0, 0}, {1, 2, 3}, {-2, 0, 1}};
  u.total_occupied = u.noccupied = 3;
  u.occupied_voxels = 3;
  auto bytes = encodeMessage(u);
  auto map = onTopic(conv.convert(channels::kMapUpdate, bytes.data(), bytes.size(), 2), "/map");
  ASSERT_EQ(map.size(), 1u);
  auto data = unbase64(json::parse(map[0].json)["data"]);
  ASSERT_EQ(data.size(), 36u);  // the mapper's three voxels, none of the cloud's
  float f[3];
  std::memcpy(f, data.data(), 12);  // key order: (-2, 0, 1) first, its centre
  EXPECT_EQ(f[0], -0.75f);
  EXPECT_EQ(f[1], 0.25f);
  EXPECT_EQ(f[2], 0.75f);
  u.seq = 2;
  u.occupied.clear();
  u.noccupied = u.total_occupied = 0;
  u.freed = {{1, 2, 3}};
  u.nfreed = u.total_freed = 1;
  bytes = encodeMessage(u);
  conv.convert(channels::kMapUpdate, bytes.data(), bytes.size(), 3);
  u.resolution_m = -1.0;  // invalid
  bytes = encodeMessage(u);
  conv.convert(channels::kMapUpdate, bytes.data(), bytes.size(), 4);
  EXPECT_EQ(conv.rejected().at(channels::kMapUpdate), 1);
  conv.convert(channels::kSweepCloud, cloud.data(), cloud.size(), 5);  // no voxels any more
  map = conv.finish(6);
  ASSERT_EQ(map.size(), 1u);
  EXPECT_EQ(unbase64(json::parse(map[0].json)["data"]).size(), 24u);
}

TEST(FoxgloveConverter, ChunkIntensitiesBecomeTheCloudsIntensityField) {
  FoxgloveConverter conv(loadRig("rig_a"));
  cloud_chunk_t c = chunk({{1.0f, 2.0f, 3.0f}, {-0.5f, 0.25f, 7.0f}});
  c.nintensities = 2;
  c.intensities = {1234.0f, 56.0f};
  const auto bytes = encodeMessage(c);
  const auto clouds =
      onTopic(conv.convert(channels::kSweepCloud, bytes.data(), bytes.size(), 0), "/sweep_cloud");
  ASSERT_EQ(clouds.size(), 1u);
  const json j = json::parse(clouds[0].json);
  EXPECT_EQ(j["point_stride"], 16);
  ASSERT_EQ(j["fields"].size(), 4u);
  EXPECT_EQ(j["fields"][3]["name"], "intensity");
  EXPECT_EQ(j["fields"][3]["offset"], 12);
  const auto data = unbase64(j["data"]);
  ASSERT_EQ(data.size(), 32u);
  float f[8];
  std::memcpy(f, data.data(), 32);
  EXPECT_EQ(f[3], 1234.0f);
  EXPECT_EQ(f[4], -0.5f);
  EXPECT_EQ(f[7], 56.0f);
}

TEST(FoxgloveConverter, ScanWithPerRayAnglesBecomesPointsInTheLidarFrame) {
  FoxgloveConverter conv(loadRig("rig_b"));
  lidar_scan_t s{};
  s.utime = 10;
  s.nranges = s.nangles = 2;
  s.ranges_m = {1.0f, 2.0f};
  s.angles_rad = {0.0f, static_cast<float>(M_PI / 2)};
  const auto bytes = encodeMessage(s);
  const auto out =
      onTopic(conv.convert(channels::kLidarScan, bytes.data(), bytes.size(), 0), "/lidar_points");
  ASSERT_EQ(out.size(), 1u);
  const auto data = unbase64(json::parse(out[0].json)["data"]);
  ASSERT_EQ(data.size(), 32u);
  float f[8];
  std::memcpy(f, data.data(), 32);
  EXPECT_FLOAT_EQ(f[2], 1.0f);    // angle 0: along Z_L
  EXPECT_NEAR(f[5], 2.0f, 1e-6);  // angle 90 deg: along Y_L
}

TEST(FoxgloveConverter, EvenScanBecomesLaserScan) {
  FoxgloveConverter conv(loadRig("rig_a"));
  lidar_scan_t s{};
  s.nranges = 3;
  s.ranges_m = {1.0f, 0.0f, 2.0f};
  s.angle_min_rad = -1.0f;
  s.angle_increment_rad = 0.5f;
  const auto bytes = encodeMessage(s);
  const auto out =
      onTopic(conv.convert(channels::kLidarScan, bytes.data(), bytes.size(), 0), "/lidar_scan");
  ASSERT_EQ(out.size(), 1u);
  const json j = json::parse(out[0].json);
  EXPECT_FLOAT_EQ(j["end_angle"].get<double>(), 0.0);
  EXPECT_EQ(j["ranges"].size(), 3u);
}

TEST(FoxgloveConverter, StatusBecomesLogAtItsHealthLevel) {
  FoxgloveConverter conv(loadRig("rig_a"));
  process_status_t st{};
  st.process = "assembler";
  st.health = process_status_t::DEGRADED;
  st.detail = "plate not found";
  st.ncounters = 1;
  st.counter_names = {"sweeps"};
  st.counter_values = {3};
  const auto bytes = encodeMessage(st);
  const auto out =
      onTopic(conv.convert("STATUS_ASSEMBLER", bytes.data(), bytes.size(), 0), "/status");
  ASSERT_EQ(out.size(), 1u);
  const json j = json::parse(out[0].json);
  EXPECT_EQ(j["level"], 3);
  EXPECT_EQ(j["name"], "assembler");
  EXPECT_NE(j["message"].get<std::string>().find("sweeps=3"), std::string::npos);
}

TEST(FoxgloveConverter, BytesThatDoNotDecodeAreCountedNotConverted) {
  FoxgloveConverter conv(loadRig("rig_a"));
  const uint8_t junk[5] = {1, 2, 3, 4, 5};
  const auto out = conv.convert(channels::kSweepCloud, junk, sizeof junk, 0);
  EXPECT_TRUE(onTopic(out, "/sweep_cloud").empty());
  EXPECT_EQ(conv.rejected().at(channels::kSweepCloud), 1);
}

}  // namespace
}  // namespace sweepmap::viz
