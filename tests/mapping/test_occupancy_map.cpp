#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

#include "mapping/occupancy_map.hpp"
#include "mapping/synthetic_room.hpp"
#include "mapping_test_util.hpp"

namespace sweepmap {
namespace {

using testing_util::fileBytes;
using testing_util::filesIn;
using testing_util::freshTestDir;

// A 4 x 3 x 2.5 m room whose walls lie on the centres of 10 cm voxels (so no wall point sits
// on a voxel boundary), seen by a coarse sweep from a sensor near its centre.
class BoxRoomTest : public ::testing::Test {
 protected:
  BoxRoomTest() {
    config_.resolution_m = 0.1;
    config_.max_range_m = 10.0;
    spec_.room_min_m = {0.05f, 0.05f, 0.05f};
    spec_.room_max_m = {4.05f, 3.05f, 2.55f};
    spec_.sensor_m = {2.05f, 1.55f, 1.35f};
    spec_.scans = 180;
    spec_.beams = 541;  // 0.5 deg steps: a few points per wall voxel even in the corners
  }

  OccupancyMap buildMap(InsertMode mode = InsertMode::kDiscretized) const {
    OccupancyMap map(config_);
    map.insertCloud(syntheticRoomSweep(spec_), spec_.sensor_m, mode);
    return map;
  }

  MapperConfig config_;
  RoomSweepSpec spec_;
};

// kDiscretized re-implements octomap's discretized insertion with a bitmap instead of a
// hash set: the same voxels must be occupied, and free space must agree to a fraction of a
// percent (ray-voxel ties may break differently).
TEST_F(BoxRoomTest, DiscretizedMatchesOctomapDiscretized) {
  spec_.range_noise_sigma_m = 0.01;
  const OccupancyMap ours = buildMap(InsertMode::kDiscretized);
  const OccupancyMap reference = buildMap(InsertMode::kOctomapDiscretized);
  const MapStats a = ours.stats(), b = reference.stats();
  EXPECT_EQ(a.occupied_voxels, b.occupied_voxels);
  EXPECT_NEAR(static_cast<double>(a.free_voxels), static_cast<double>(b.free_voxels),
              0.005 * static_cast<double>(b.free_voxels));
  int checked = 0;
  for (double x = 0.0; x <= 4.1; x += 0.1) {
    for (double y = 0.0; y <= 3.1; y += 0.1) {
      for (double z = 0.0; z <= 2.6; z += 0.1) {
        const Eigen::Vector3d p(x + 0.05, y + 0.05, z + 0.05);
        EXPECT_EQ(ours.occupiedAt(p), reference.occupiedAt(p)) << p.transpose();
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 30000);
}

TEST_F(BoxRoomTest, WallsOccupiedInteriorFree) {
  for (InsertMode mode : {InsertMode::kDiscretized, InsertMode::kEveryRay}) {
    SCOPED_TRACE(mode == InsertMode::kDiscretized ? "discretized" : "every ray");
    const OccupancyMap map = buildMap(mode);
    // Walls, ceiling and the floor away from the blind cone below the sensor.
    for (const Eigen::Vector3d& p :
         {Eigen::Vector3d(0.05, 1.55, 1.35), Eigen::Vector3d(4.05, 1.05, 0.85),
          Eigen::Vector3d(2.05, 0.05, 2.05), Eigen::Vector3d(1.05, 3.05, 1.35),
          Eigen::Vector3d(2.05, 1.55, 2.55), Eigen::Vector3d(0.55, 0.55, 0.05),
          Eigen::Vector3d(3.55, 2.55, 0.05)}) {
      EXPECT_EQ(map.occupancyAt(p), Occupancy::kOccupied) << p.transpose();
    }
    // Inside, on the way to the walls.
    for (const Eigen::Vector3d& p :
         {Eigen::Vector3d(1.05, 1.55, 1.35), Eigen::Vector3d(3.05, 2.05, 1.85),
          Eigen::Vector3d(0.55, 0.55, 0.55), Eigen::Vector3d(2.05, 1.55, 2.25),
          Eigen::Vector3d(3.75, 2.75, 2.25)}) {
      EXPECT_EQ(map.occupancyAt(p), Occupancy::kFree) << p.transpose();
    }
    // Never seen: outside the room, and the cone straight below the sensor (270 deg fan).
    EXPECT_EQ(map.occupancyAt({5.05, 1.55, 1.35}), Occupancy::kUnknown);
    EXPECT_EQ(map.occupancyAt({2.05, 1.55, 0.35}), Occupancy::kUnknown);
    EXPECT_FALSE(map.occupiedAt({std::nan(""), 0.0, 0.0}));
  }
}

TEST_F(BoxRoomTest, StatsAreSane) {
  const OccupancyMap map = buildMap();
  const MapStats s = map.stats();
  EXPECT_EQ(s.sweeps_inserted, 1);
  EXPECT_EQ(s.points_inserted, int64_t{spec_.scans} * spec_.beams);
  EXPECT_DOUBLE_EQ(s.resolution_m, 0.1);
  // Surface 2 (4*3 + 4*2.5 + 3*2.5) = 59 m^2 = 5900 voxels of 10 cm, less the unseen floor.
  EXPECT_GT(s.occupied_voxels, 4000);
  EXPECT_LT(s.occupied_voxels, 7000);
  // Volume 30 m^3 = 30000 voxels, less the walls and the blind cone.
  EXPECT_GT(s.free_voxels, 20000);
  EXPECT_LT(s.free_voxels, 30000);
  EXPECT_GT(s.memory_bytes, 0);
  EXPECT_EQ(map.skippedPoints(), 0);
}

TEST(OccupancyMap, PointsBeyondMaxRangeOnlyClearSpace) {
  MapperConfig config;
  config.resolution_m = 0.1;
  config.max_range_m = 2.0;
  OccupancyMap map(config);
  const Eigen::Vector3f origin(0.05f, 0.05f, 0.05f);
  map.insertCloud({{5.05f, 0.05f, 0.05f}, {0.05f, 1.55f, 0.05f}}, origin);
  EXPECT_EQ(map.occupancyAt({5.05, 0.05, 0.05}), Occupancy::kUnknown);  // beyond: no hit
  EXPECT_EQ(map.occupancyAt({1.05, 0.05, 0.05}), Occupancy::kFree);     // the ray, cut at 2 m
  EXPECT_EQ(map.occupancyAt({3.05, 0.05, 0.05}), Occupancy::kUnknown);
  EXPECT_EQ(map.occupancyAt({0.05, 1.55, 0.05}), Occupancy::kOccupied);  // within range
  EXPECT_EQ(map.stats().occupied_voxels, 1);
}

TEST(OccupancyMap, NonFinitePointsAreSkippedAndCounted) {
  MapperConfig config;
  config.resolution_m = 0.1;
  OccupancyMap map(config);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  map.insertCloud({{1.05f, 0.05f, 0.05f},
                   {nan, 0.0f, 0.0f},
                   {0.0f, inf, 0.0f},
                   {0.05f, 0.05f, -inf},
                   {0.05f, 1.05f, 0.05f}},
                  {0.05f, 0.05f, 0.05f});
  EXPECT_EQ(map.skippedPoints(), 3);
  EXPECT_EQ(map.stats().points_inserted, 2);
  EXPECT_TRUE(map.occupiedAt({1.05, 0.05, 0.05}));
  EXPECT_TRUE(map.occupiedAt({0.05, 1.05, 0.05}));
  EXPECT_THROW(map.insertCloud({{1.0f, 0.0f, 0.0f}}, {nan, 0.0f, 0.0f}), std::invalid_argument);
}

TEST(OccupancyMap, RejectsBadConfig) {
  MapperConfig c;
  c.resolution_m = 0.0;
  EXPECT_THROW(OccupancyMap{c}, std::invalid_argument);
  c = MapperConfig{};
  c.prob_hit = 0.4;
  EXPECT_THROW(OccupancyMap{c}, std::invalid_argument);
  c = MapperConfig{};
  c.clamp_min = 0.98;
  EXPECT_THROW(OccupancyMap{c}, std::invalid_argument);
}

TEST_F(BoxRoomTest, SameInputGivesIdenticalBtFiles) {
  const auto dir = freshTestDir();
  spec_.range_noise_sigma_m = 0.012;
  const auto a = dir / "a.bt";
  const auto b = dir / "b.bt";
  for (const auto& path : {a, b}) {
    OccupancyMap map(config_);
    for (uint32_t seed : {1u, 2u, 3u}) {
      spec_.seed = seed;
      map.insertCloud(syntheticRoomSweep(spec_), spec_.sensor_m);
      EXPECT_TRUE(map.matchesOctomapReference());
    }
    map.saveBinaryAtomic(path.string());
  }
  const std::string bytes_a = fileBytes(a);
  ASSERT_GT(bytes_a.size(), 1000u);
  EXPECT_EQ(bytes_a, fileBytes(b));
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{"a.bt", "b.bt"}));  // no .tmp left

  const OccupancyMap loaded = OccupancyMap::loadBinary(a.string());
  EXPECT_DOUBLE_EQ(loaded.config().resolution_m, 0.1);
  EXPECT_TRUE(loaded.occupiedAt({0.05, 1.55, 1.35}));
  EXPECT_EQ(loaded.occupancyAt({1.05, 1.55, 1.35}), Occupancy::kFree);
  EXPECT_EQ(loaded.occupancyAt({5.05, 1.55, 1.35}), Occupancy::kUnknown);
}

// insertClouds() shares only the whole-tree updates between clouds: many small clouds
// from moving origins (like rig B's scans), some overlapping and some repeating voxels,
// give the same tree, byte for byte, as insertCloud() one by one.
TEST_F(BoxRoomTest, InsertCloudsEqualsInsertCloudOneByOne) {
  const auto dir = freshTestDir();
  spec_.range_noise_sigma_m = 0.012;
  spec_.scans = 6;
  spec_.beams = 181;
  std::vector<SensorCloud> clouds;
  for (int k = 0; k < 12; ++k) {
    spec_.seed = static_cast<uint32_t>(k + 1);
    spec_.sensor_m = {1.0f + 0.03f * static_cast<float>(k), 1.55f, 1.35f};
    clouds.push_back({syntheticRoomSweep(spec_), spec_.sensor_m});
  }
  OccupancyMap one_by_one(config_), batched(config_), two_batches(config_);
  for (const SensorCloud& c : clouds) one_by_one.insertCloud(c.points_m, c.origin_m);
  std::vector<size_t> rejected;
  batched.insertClouds(clouds, &rejected);
  EXPECT_TRUE(rejected.empty());
  two_batches.insertClouds({clouds.begin(), clouds.begin() + 5});
  two_batches.insertClouds({clouds.begin() + 5, clouds.end()});
  const MapStats a = one_by_one.stats(), b = batched.stats();
  EXPECT_EQ(a.sweeps_inserted, b.sweeps_inserted);
  EXPECT_EQ(a.points_inserted, b.points_inserted);
  EXPECT_EQ(a.occupied_voxels, b.occupied_voxels);
  EXPECT_EQ(a.free_voxels, b.free_voxels);
  EXPECT_EQ(a.memory_bytes, b.memory_bytes);
  EXPECT_GT(a.occupied_voxels, 100);
  for (const auto& [name, map] :
       {std::pair<const char*, const OccupancyMap*>{"one.bt", &one_by_one},
        {"batched.bt", &batched},
        {"two.bt", &two_batches}}) {
    map->saveBinaryAtomic((dir / name).string());
  }
  // The one-pass inner update, pruning and counting equal OctoMap's own passes.
  EXPECT_TRUE(one_by_one.matchesOctomapReference());
  EXPECT_TRUE(batched.matchesOctomapReference());
  EXPECT_TRUE(two_batches.matchesOctomapReference());
  const std::string reference = fileBytes(dir / "one.bt");
  ASSERT_GT(reference.size(), 1000u);
  EXPECT_EQ(reference, fileBytes(dir / "batched.bt"));
  EXPECT_EQ(reference, fileBytes(dir / "two.bt"));
}

// The one-pass update walks only the regions (3.2 m cubes at 10 cm) an insertion touched
// and reuses the counts of the others. Three rooms 12 m apart are seen in turn, so most
// regions are untouched in each batch; over many batches free space is clamped and pruned
// into large nodes, and split again by an obstacle that appears and goes. The tree and
// the counts must stay what OctoMap's own whole-tree passes give.
TEST_F(BoxRoomTest, TouchedRegionsOnlyMatchOctomapOverManyBatches) {
  spec_.scans = 8;
  spec_.beams = 91;
  OccupancyMap map(config_);
  const RoomSweepSpec room = spec_;
  for (int batch = 0; batch < 36; ++batch) {
    const Eigen::Vector3f offset(12.0f * static_cast<float>(batch % 3), 0.0f, 0.0f);
    std::vector<SensorCloud> clouds;
    for (int k = 0; k < 3; ++k) {
      RoomSweepSpec spec = room;
      spec.room_min_m += offset;
      spec.room_max_m += offset;
      spec.seed = static_cast<uint32_t>(batch * 3 + k + 1);
      spec.range_noise_sigma_m = batch < 24 ? 0.0 : 0.02;
      spec.sensor_m = offset + Eigen::Vector3f(0.8f + 0.1f * static_cast<float>((batch + k) % 25),
                                               1.55f, 1.35f);
      SensorCloud c{syntheticRoomSweep(spec), spec.sensor_m};
      if (batch >= 12 && batch < 20) {  // an obstacle in the middle of the (pruned) free space
        for (float y = 0.5f; y < 1.2f; y += 0.05f) {
          for (float z = 0.5f; z < 1.2f; z += 0.05f)
            c.points_m.push_back(offset + Eigen::Vector3f(3.55f, y, z));
        }
      }
      clouds.push_back(std::move(c));
    }
    map.insertClouds(clouds);
    ASSERT_TRUE(map.matchesOctomapReference()) << "after batch " << batch;
  }
  const MapStats s = map.stats();
  EXPECT_EQ(s.sweeps_inserted, 108);
  EXPECT_GT(s.occupied_voxels, 3 * 1000);
}

TEST(OccupancyMap, InsertCloudsSkipsBadOriginsAndInsertsTheRest) {
  MapperConfig config;
  config.resolution_m = 0.1;
  OccupancyMap map(config);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<size_t> rejected;
  map.insertClouds({{{{1.05f, 0.05f, 0.05f}}, {0.05f, 0.05f, 0.05f}},
                    {{{2.05f, 0.05f, 0.05f}}, {nan, 0.05f, 0.05f}},
                    {{{3.05f, 0.05f, 0.05f}}, {1e7f, 0.05f, 0.05f}},
                    {{{0.05f, 1.05f, 0.05f}}, {0.05f, 0.05f, 0.05f}}},
                   &rejected);
  EXPECT_EQ(rejected, (std::vector<size_t>{1, 2}));
  EXPECT_EQ(map.stats().sweeps_inserted, 2);
  EXPECT_TRUE(map.occupiedAt({1.05, 0.05, 0.05}));
  EXPECT_TRUE(map.occupiedAt({0.05, 1.05, 0.05}));
  EXPECT_EQ(map.occupancyAt({2.05, 0.05, 0.05}), Occupancy::kUnknown);
  EXPECT_EQ(map.occupancyAt({3.05, 0.05, 0.05}), Occupancy::kUnknown);
}

TEST_F(BoxRoomTest, SaveReplacesAndReportsFailures) {
  const auto dir = freshTestDir();
  const auto path = dir / "map.bt";
  const OccupancyMap map = buildMap();
  map.saveBinaryAtomic(path.string());
  map.saveBinaryAtomic(path.string());  // replacing an existing file
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"map.bt"});

  const std::string bad = (dir / "no_such_dir" / "map.bt").string();
  try {
    map.saveBinaryAtomic(bad);
    FAIL() << "saving into a missing folder must throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
  EXPECT_THROW(OccupancyMap::loadBinary((dir / "missing.bt").string()), std::runtime_error);
}

// Saving prints nothing (Debian 12's liboctomap says " done." on stderr after every
// writeBinaryConst()), and the file holds exactly the bytes OctoMap's own writer makes.
TEST_F(BoxRoomTest, SaveIsSilentAndWritesOctoMapsOwnBytes) {
  const auto dir = freshTestDir();
  const auto path = dir / "map.bt";
  const OccupancyMap map = buildMap();
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  map.saveBinaryAtomic(path.string());
  const std::string out = testing::internal::GetCapturedStdout();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(out + err, "");

  std::ifstream in(path, std::ios::binary);
  const std::string saved((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  octomap::OcTree tree(0.1);
  std::istringstream read(saved);
  ASSERT_TRUE(tree.readBinary(read));
  EXPECT_GT(tree.size(), 100u);
  std::ostringstream theirs;
  ASSERT_TRUE(tree.writeBinaryConst(theirs));
  EXPECT_TRUE(saved == theirs.str())
      << saved.size() << " bytes saved, OctoMap writes " << theirs.str().size();
}

}  // namespace
}  // namespace sweepmap
