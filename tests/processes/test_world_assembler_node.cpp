#include <gtest/gtest.h>

#include <cmath>

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/world_assembler_node.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "tests/processes/node_test_util.hpp"

namespace sweepmap {
namespace {

using test::encode;

Message pose(int64_t utime, double x) {
  pose2d_t p{};
  p.utime = utime;
  p.x_m = x;
  return encode(channels::kOdometryPose, p);
}

Message scan(int64_t utime, std::vector<float> intensities = {}) {
  Scan2D s;
  s.intensities = std::move(intensities);
  s.utime = utime;
  s.angle_min_rad = -0.1;
  s.angle_increment_rad = 0.1;
  s.time_increment_ns = 1000000;
  s.range_min_m = 0.02;
  s.range_max_m = 10;
  s.ranges_m = {2.0f, 2.0f, 2.0f};
  return encode(channels::kLidarScan, toLcm(s));
}

std::vector<cloud_chunk_t> feed(WorldAssemblerNode& node, const std::vector<Message>& msgs) {
  std::vector<cloud_chunk_t> out;
  for (const auto& m : msgs) {
    Outbox o;
    node.receive(m, o);
    for (const auto& r : o.take()) {
      cloud_chunk_t c;
      if (r.channel == channels::kSweepCloud && decodeMessage(r, &c)) out.push_back(c);
    }
  }
  return out;
}

WorldAssemblerNode horizontal(double lidar_time_offset_s = 0.0) {
  WorldAssemblerConfig c;
  c.lidar_time_offset_s = lidar_time_offset_s;
  LidarMounting m;
  m.nominal_rpy_rad = Eigen::Vector3d(0, M_PI / 2, 0);
  m.t_BL_m = Eigen::Vector3d(0.1, 0, 0.2);
  return WorldAssemblerNode(c, m);
}

TEST(WorldAssemblerNode, WaitsForPosesThenPublishesWorldChunks) {
  WorldAssemblerNode node = horizontal();
  auto chunks = feed(node, {pose(0, 0.0), scan(1000)});
  EXPECT_TRUE(chunks.empty()) << "published before the poses covered the scan";
  chunks = feed(node, {pose(10000, 1.0)});
  ASSERT_EQ(chunks.size(), 1u);
  const auto& c = chunks[0];
  EXPECT_EQ(c.frame, "world");
  EXPECT_EQ(c.npoints, 3);
  // Middle ray (angle 0) at t = 2 ms: robot at x = 0.2 m; the point 2 m ahead of the lidar.
  EXPECT_NEAR(c.xyz_m[1][0], 0.2 + 0.1 + 2.0, 1e-5);
  EXPECT_NEAR(c.xyz_m[1][2], 0.2, 1e-6);
  EXPECT_NEAR(c.sensor_origin_m[0], 0.3, 1e-9);
  EXPECT_EQ(c.nintensities, 0);  // the scan had none
}

// lidar.time_offset_s: the lidar's stamps run 4 ms ahead of the odometry's clock, so the middle
// ray stamped 6 ms was taken at 2 ms, where the robot was at x = 0.2 m (as in the test above),
// not 0.6 m; the chunk is stamped on the odometry's clock.
TEST(WorldAssemblerNode, PlacesEachRayWithThePoseAtItsStampLessTheLidarsTimeOffset) {
  WorldAssemblerNode node = horizontal(0.004);
  const auto chunks = feed(node, {pose(0, 0.0), scan(5000), pose(10000, 1.0)});
  ASSERT_EQ(chunks.size(), 1u);
  EXPECT_NEAR(chunks[0].xyz_m[1][0], 0.2 + 0.1 + 2.0, 1e-5);
  EXPECT_EQ(chunks[0].utime, 1000);
}

TEST(WorldAssemblerNode, ChunksCarryTheScansIntensities) {
  WorldAssemblerNode node = horizontal();
  std::vector<float> seen;
  node.setObserver([&](int64_t, const std::vector<Eigen::Vector3f>&,
                       const std::vector<float>& intensities,
                       const Eigen::Vector3d&) { seen = intensities; });
  const auto chunks = feed(node, {pose(0, 0.0), scan(1000, {5.0f, 6.0f, 7.0f}), pose(10000, 1.0)});
  ASSERT_EQ(chunks.size(), 1u);
  EXPECT_EQ(chunks[0].nintensities, 3);
  EXPECT_EQ(chunks[0].intensities, (std::vector<float>{5.0f, 6.0f, 7.0f}));
  EXPECT_EQ(seen, chunks[0].intensities);
}

TEST(WorldAssemblerNode, BadPosesAndScansCounted) {
  WorldAssemblerNode node = horizontal();
  pose2d_t p{};
  p.x_m = std::nan("");
  feed(node, {encode(channels::kOdometryPose, p), Message{0, channels::kLidarScan, {1, 2}},
              Message{0, channels::kOdometryPose, {3}}});
  EXPECT_EQ(node.counter("invalid"), 3);
  // Without poses, finish() drops the rays and counts them.
  feed(node, {scan(1000)});
  Outbox out;
  node.finish(0, out);
  EXPECT_EQ(node.counter("rays_without_pose"), 3);
}

}  // namespace
}  // namespace sweepmap
