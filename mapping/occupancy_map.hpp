// 3D occupancy map of sweeps: a thin wrapper over an OctoMap OcTree.
//
// Frames and units: every point and origin is in the map (world) frame, in metres. The
// caller transforms sweeps into that frame before insertion. OctoMap is kept out of this
// header (pimpl) so that code including it does not pull in the OctoMap headers.
//
// Not thread-safe: one thread owns a map (insertion is heavy work; run it off the
// receive path, see STYLE.md rule 7).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/rig_components.hpp"

namespace sweepmap {

struct MapStats {
  int64_t sweeps_inserted = 0;  // insertCloud() calls
  int64_t points_inserted = 0;  // finite points handed to the tree (skipped ones excluded)
  int64_t occupied_voxels = 0;  // counted at full depth (a pruned leaf counts as 8^k voxels)
  int64_t free_voxels = 0;      // known and not occupied, counted at full depth
  int64_t memory_bytes = 0;     // OctoMap's estimate of the tree's memory
  double resolution_m = 0.0;    // edge of a full-depth voxel
};

// How the rays of one cloud are cast.
enum class InsertMode {
  kDiscretized,         // one ray per distinct endpoint voxel, to its centre (default; see .cpp)
  kEveryRay,            // one ray per point, to the exact point
  kOctomapDiscretized,  // octomap's own discretized insertion (reference for kDiscretized)
};

enum class Occupancy { kUnknown, kFree, kOccupied };

// One cloud and the sensor origin its rays start from (map frame, metres).
struct SensorCloud {
  std::vector<Eigen::Vector3f> points_m;
  Eigen::Vector3f origin_m = Eigen::Vector3f::Zero();
};

// A full-depth voxel by its integer index per axis: it spans [i * res, (i + 1) * res) in the map
// frame, its centre is (i + 0.5) * res. Ordered x, then y, then z.
using VoxelIndex = std::array<int32_t, 3>;

// What insertions changed since the last takeChanges(): each list sorted, no voxel in both.
struct VoxelChanges {
  std::vector<VoxelIndex> occupied;  // occupied now, not before
  std::vector<VoxelIndex> freed;     // occupied before, free now
};

class OccupancyMap {
 public:
  // Throws std::invalid_argument if the config is out of range (resolution and max range
  // must be > 0, 0.5 < prob_hit < 1, 0 < prob_miss < 0.5, 0 < clamp_min < clamp_max < 1).
  explicit OccupancyMap(const MapperConfig& config);
  ~OccupancyMap();
  OccupancyMap(OccupancyMap&&) noexcept;
  OccupancyMap& operator=(OccupancyMap&&) noexcept;
  OccupancyMap(const OccupancyMap&) = delete;
  OccupancyMap& operator=(const OccupancyMap&) = delete;

  // Ray-casts one cloud (typically one sweep) from `sensor_origin_m`: the endpoint voxels
  // become more occupied, the voxels along the rays more free; each voxel is updated at
  // most once per call, occupied winning over free. Rays longer than config.max_range_m
  // are cut at that range and mark free space only. Non-finite points are skipped and
  // counted (skippedPoints()). Deterministic: the same calls in the same order build an
  // identical tree. Throws std::invalid_argument for a non-finite origin.
  void insertCloud(const std::vector<Eigen::Vector3f>& points_m,
                   const Eigen::Vector3f& sensor_origin_m,
                   InsertMode mode = InsertMode::kDiscretized);

  // Inserts several clouds, each ray-cast from its own origin exactly as insertCloud()
  // would (kDiscretized), but brings the tree's inner nodes and pruning up to date once at
  // the end instead of after every cloud. The tree is the same as that of insertCloud()
  // for each cloud in turn, byte for byte: lazy leaf updates do not depend on inner
  // nodes, and pruning is lossless (a pruned node is expanded with its value when a voxel
  // inside it is updated), so the final pruned tree depends only on the voxels' values.
  // What it saves is the whole-tree passes (updateInnerOccupancy, prune), which dominate
  // for small clouds such as the single scans of rig B. A cloud with a non-finite origin or
  // one outside the map is not inserted (and not counted): its index goes to `rejected`.
  void insertClouds(const std::vector<SensorCloud>& clouds,
                    std::vector<size_t>* rejected = nullptr);

  // Kept up to date by every insertion (the same pass that updates the inner nodes); for a
  // loaded map it walks every leaf.
  MapStats stats() const;

  // A check for tests: whether the tree equals, node for node and value for value, what
  // OctoMap's own updateInnerOccupancy() + prune() make of its leaves, and stats() what
  // OctoMap's leaf iterator and memoryUsage() give. Copies the whole tree.
  bool matchesOctomapReference() const;
  int64_t skippedPoints() const;
  const MapperConfig& config() const;

  // Starts recording which voxels change occupancy, for takeChanges(): a set of the occupied
  // voxels is kept beside the tree, updated by each leaf update that can change a voxel's
  // occupancy (see ChangeTracker in the .cpp; cheaper than OctoMap's change detection, which
  // notes every new free leaf).
  void trackChanges();
  // The voxels whose occupancy changed since trackChanges() or the last takeChanges(), judged
  // on the tree as it is now (a voxel that flipped and flipped back is in neither list); the
  // record starts again empty. Applied in turn to an empty set, the changes give exactly
  // occupiedVoxels(). Empty lists when not tracking.
  VoxelChanges takeChanges();
  // Every occupied full-depth voxel (a pruned block of 8^k voxels as its 8^k voxels), sorted.
  std::vector<VoxelIndex> occupiedVoxels() const;
  // The same voxels from the change tracking's set, without walking the tree (what a full
  // MAP_UPDATE sends); occupiedVoxels() when not tracking.
  std::vector<VoxelIndex> trackedVoxels() const;

  // Centres of the occupied leaves [m] (a pruned block of occupied voxels: its centre), in the
  // tree's order (deterministic): what the report's 3D map picture draws.
  std::vector<Eigen::Vector3f> occupiedCentres() const;

  // State of the full-depth voxel containing `p_m` (map frame, metres).
  Occupancy occupancyAt(const Eigen::Vector3d& p_m) const;
  bool occupiedAt(const Eigen::Vector3d& p_m) const {
    return occupancyAt(p_m) == Occupancy::kOccupied;
  }

  // Writes the maximum-likelihood tree in OctoMap's binary format (.bt, readable by
  // octovis) to `path + ".tmp"`, then renames it over `path`. Throws std::runtime_error
  // naming `path` on failure.
  void saveBinaryAtomic(const std::string& path) const;

  // Reads a .bt file (resolution from the file; the other config fields keep their
  // defaults; the counters start at zero). Throws std::runtime_error naming `path`.
  static OccupancyMap loadBinary(const std::string& path);

 private:
  struct Impl;
  explicit OccupancyMap(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace sweepmap
