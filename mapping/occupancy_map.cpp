#include "mapping/occupancy_map.hpp"

#include <octomap/OcTree.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "mapping/atomic_file.hpp"

namespace sweepmap {
namespace {

void validate(const MapperConfig& c) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("MapperConfig: " + what); };
  if (!(c.resolution_m > 0.0)) fail("resolution_m must be > 0");
  if (!(c.max_range_m > 0.0)) fail("max_range_m must be > 0");
  if (!(c.prob_hit > 0.5 && c.prob_hit < 1.0)) fail("prob_hit must be in (0.5, 1)");
  if (!(c.prob_miss > 0.0 && c.prob_miss < 0.5)) fail("prob_miss must be in (0, 0.5)");
  if (!(c.clamp_min > 0.0 && c.clamp_min < c.clamp_max && c.clamp_max < 1.0)) {
    fail("need 0 < clamp_min < clamp_max < 1");
  }
}

}  // namespace

struct OccupancyMap::Impl {
  explicit Impl(const MapperConfig& c) : config(c), tree(c.resolution_m) {
    tree.setProbHit(c.prob_hit);
    tree.setProbMiss(c.prob_miss);
    tree.setClampingThresMin(c.clamp_min);
    tree.setClampingThresMax(c.clamp_max);
  }

  MapperConfig config;
  octomap::OcTree tree;
  int64_t sweeps = 0;
  int64_t points = 0;
  int64_t skipped = 0;
  octomap::Pointcloud scratch;  // reused between calls to avoid reallocating ~10 MB per sweep
};

OccupancyMap::OccupancyMap(const MapperConfig& config)
    : impl_((validate(config), std::make_unique<Impl>(config))) {}
OccupancyMap::OccupancyMap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

void OccupancyMap::insertCloud(const std::vector<Eigen::Vector3f>& points_m,
                               const Eigen::Vector3f& sensor_origin_m, InsertMode mode) {
  if (!sensor_origin_m.allFinite()) {
    throw std::invalid_argument("OccupancyMap::insertCloud: non-finite sensor origin");
  }
  octomap::Pointcloud& cloud = impl_->scratch;
  cloud.clear();
  cloud.reserve(points_m.size());
  for (const Eigen::Vector3f& p : points_m) {
    if (!p.allFinite()) {
      ++impl_->skipped;
      continue;
    }
    cloud.push_back(p.x(), p.y(), p.z());
  }
  const octomap::point3d origin(sensor_origin_m.x(), sensor_origin_m.y(), sensor_origin_m.z());

  // Discretization (the default) first collapses the endpoints to distinct voxel keys and
  // casts one ray per key, to the voxel's centre. A sweep of a rotating 2D lidar is very
  // uneven: near the rotation axis and on nearby surfaces dozens of points fall into the
  // same 5 cm voxel, and every extra ray costs range/resolution key steps while adding no
  // evidence (OctoMap updates each voxel at most once per insertion anyway). The cost in
  // quality is small: the occupied voxels are exactly the same; only the free voxels along
  // grazing rays can differ, since a ray ends at the centre of its endpoint voxel instead
  // of the point, i.e. up to half a voxel off. bench_mapping measures the speed-up.
  //
  // Determinism: the Debian liboctomap is built without OpenMP, so insertion runs in one
  // thread; and each voxel gets exactly one log-odds update per call, so the result does
  // not depend on the order of the (hash-set ordered) updates either way.
  const bool discretize = mode == InsertMode::kDiscretized;
  impl_->tree.insertPointCloud(cloud, origin, impl_->config.max_range_m, /*lazy_eval=*/false,
                               discretize);
  impl_->points += static_cast<int64_t>(cloud.size());
  ++impl_->sweeps;
}

MapStats OccupancyMap::stats() const {
  const octomap::OcTree& tree = impl_->tree;
  MapStats s;
  s.sweeps_inserted = impl_->sweeps;
  s.points_inserted = impl_->points;
  s.resolution_m = tree.getResolution();
  s.memory_bytes = static_cast<int64_t>(tree.memoryUsage());
  const unsigned max_depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    // A leaf above full depth (pruned: all children equal) stands for 8^(levels) voxels.
    const int64_t voxels = int64_t{1} << (3 * (max_depth - it.getDepth()));
    if (tree.isNodeOccupied(*it)) {
      s.occupied_voxels += voxels;
    } else {
      s.free_voxels += voxels;
    }
  }
  return s;
}

int64_t OccupancyMap::skippedPoints() const { return impl_->skipped; }

const MapperConfig& OccupancyMap::config() const { return impl_->config; }

Occupancy OccupancyMap::occupancyAt(const Eigen::Vector3d& p_m) const {
  if (!p_m.allFinite()) return Occupancy::kUnknown;
  octomap::OcTreeKey key;
  if (!impl_->tree.coordToKeyChecked(p_m.x(), p_m.y(), p_m.z(), key)) return Occupancy::kUnknown;
  const octomap::OcTreeNode* node = impl_->tree.search(key);
  if (node == nullptr) return Occupancy::kUnknown;
  return impl_->tree.isNodeOccupied(node) ? Occupancy::kOccupied : Occupancy::kFree;
}

void OccupancyMap::saveBinaryAtomic(const std::string& path) const {
  // Serialise in memory first (a room at 5 cm is a few MB), so that a failure leaves
  // neither a partial file nor a temporary one. writeBinaryConst() does not prune or
  // modify the tree, unlike writeBinary().
  std::ostringstream bytes(std::ios::binary);
  if (!impl_->tree.writeBinaryConst(bytes)) {
    throw std::runtime_error("cannot save " + path + ": OctoMap serialisation failed");
  }
  writeFileAtomic(path, bytes.str());
}

OccupancyMap OccupancyMap::loadBinary(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path);
  MapperConfig config;
  auto impl = std::make_unique<Impl>(config);
  if (!impl->tree.readBinary(in)) {
    throw std::runtime_error("cannot read " + path + ": not an OctoMap binary (.bt) file");
  }
  impl->config.resolution_m = impl->tree.getResolution();
  return OccupancyMap(std::move(impl));
}

}  // namespace sweepmap
