#include "mapping/occupancy_map.hpp"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "core/atomic_file.hpp"

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

// Keys of the voxels an insertion touches, as bits over the key box of one sweep: marking a
// ray's voxels costs a shift and an OR instead of a hash-set insertion.
class KeyBitmap {
 public:
  KeyBitmap(const octomap::OcTreeKey& lo, const octomap::OcTreeKey& hi) : lo_(lo) {
    for (int i = 0; i < 3; ++i) n_[i] = static_cast<size_t>(hi[i] - lo[i]) + 1;
    bits_.assign((n_[0] * n_[1] * n_[2] + 63) / 64, 0);
  }
  bool inside(const octomap::OcTreeKey& k) const {
    for (int i = 0; i < 3; ++i) {
      if (k[i] < lo_[i] || static_cast<size_t>(k[i] - lo_[i]) >= n_[i]) return false;
    }
    return true;
  }
  // Keys outside the box (a ray's last step at a voxel corner) are ignored.
  void set(const octomap::OcTreeKey& k) {
    if (!inside(k)) return;
    const size_t i = index(k);
    bits_[i >> 6] |= uint64_t{1} << (i & 63);
  }
  bool test(const octomap::OcTreeKey& k) const {
    if (!inside(k)) return false;
    const size_t i = index(k);
    return (bits_[i >> 6] >> (i & 63)) & 1u;
  }
  // Calls f(key) for every set bit, in index order (deterministic).
  template <class F>
  void forEach(F&& f) const {
    for (size_t w = 0; w < bits_.size(); ++w) {
      for (uint64_t word = bits_[w]; word != 0; word &= word - 1) {
        const size_t i = w * 64 + static_cast<size_t>(__builtin_ctzll(word));
        octomap::OcTreeKey k;
        k[0] = static_cast<octomap::key_type>(lo_[0] + i % n_[0]);
        k[1] = static_cast<octomap::key_type>(lo_[1] + (i / n_[0]) % n_[1]);
        k[2] = static_cast<octomap::key_type>(lo_[2] + i / (n_[0] * n_[1]));
        f(k);
      }
    }
  }

 private:
  size_t index(const octomap::OcTreeKey& k) const {
    return (static_cast<size_t>(k[2] - lo_[2]) * n_[1] + static_cast<size_t>(k[1] - lo_[1])) *
               n_[0] +
           static_cast<size_t>(k[0] - lo_[0]);
  }
  octomap::OcTreeKey lo_;
  size_t n_[3];
  std::vector<uint64_t> bits_;
};

// Marks the voxels of the ray from `origin` to `end` (excluding the end voxel), like
// octomap's computeRayKeys (3D DDA of Amanatides & Woo).
void markRay(const octomap::OcTree& tree, const octomap::point3d& origin,
             const octomap::point3d& end, KeyBitmap* bits) {
  octomap::OcTreeKey key, end_key;
  if (!tree.coordToKeyChecked(origin, key) || !tree.coordToKeyChecked(end, end_key)) return;
  if (key == end_key) return;
  bits->set(key);
  octomap::point3d dir = end - origin;
  const double length = dir.norm();
  dir /= static_cast<float>(length);
  const double res = tree.getResolution();
  int step[3];
  double t_max[3], t_delta[3];
  for (int i = 0; i < 3; ++i) {
    step[i] = dir(i) > 0 ? 1 : (dir(i) < 0 ? -1 : 0);
    if (step[i] != 0) {
      const double border = tree.keyToCoord(key[i]) + step[i] * res * 0.5;
      t_max[i] = (border - origin(i)) / dir(i);
      t_delta[i] = res / std::abs(dir(i));
    } else {
      t_max[i] = t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  while (true) {
    const int dim =
        t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    key[dim] = static_cast<octomap::key_type>(key[dim] + step[dim]);
    t_max[dim] += t_delta[dim];
    if (key == end_key) break;
    if (std::min({t_max[0], t_max[1], t_max[2]}) - t_delta[dim] > length) break;
    bits->set(key);
  }
}

// Voxels and leaves under a node, counted at full depth (a leaf above full depth, pruned
// because its children were equal, stands for 8^levels voxels).
struct LeafCounts {
  int64_t occupied_voxels = 0;
  int64_t free_voxels = 0;
  int64_t leaves = 0;
};

void countLeaf(const octomap::OcTree& tree, const octomap::OcTreeNode* leaf, unsigned depth,
               LeafCounts* c) {
  const int64_t voxels = int64_t{1} << (3 * (tree.getTreeDepth() - depth));
  (tree.isNodeOccupied(leaf) ? c->occupied_voxels : c->free_voxels) += voxels;
  ++c->leaves;
}

void countRecurs(const octomap::OcTree& tree, const octomap::OcTreeNode* node, unsigned depth,
                 LeafCounts* c) {
  if (!tree.nodeHasChildren(node)) return countLeaf(tree, node, depth, c);
  for (unsigned i = 0; i < 8; ++i) {
    if (tree.nodeChildExists(node, i)) countRecurs(tree, tree.getNodeChild(node, i), depth + 1, c);
  }
}

// After lazy leaf updates: what tree.updateInnerOccupancy() followed by tree.prune() make of
// the tree, and the leaf counts, in one post-order pass instead of three whole-tree passes
// (updateInnerOccupancy, prune, then stats() with memoryUsage()'s leaf count). Every inner
// node gets the maximum of its children, and every node but the root whose eight children
// are equal leaves is pruned, bottom-up. OctoMap's prune() also collapses bottom-up, depth by
// depth, and stops at a depth where nothing was pruned; starting from a fully pruned tree,
// as every insertion here leaves it, a collapsible node at one depth needs a prune below it
// in the same pass, so both end fully pruned: the same tree (matchesOctomapReference()).
void finalizeRecurs(octomap::OcTree& tree, octomap::OcTreeNode* node, unsigned depth,
                    LeafCounts* c) {
  if (!tree.nodeHasChildren(node)) return countLeaf(tree, node, depth, c);
  for (unsigned i = 0; i < 8; ++i) {
    if (tree.nodeChildExists(node, i))
      finalizeRecurs(tree, tree.getNodeChild(node, i), depth + 1, c);
  }
  if (depth > 0 && tree.pruneNode(node)) {
    c->leaves -= 7;  // eight leaves became one; the voxels they stand for are the same
    return;
  }
  node->updateOccupancyChildren();
}

// An OcTree key in one integer (z, y, x: 16 bits each), for hashing and sorting; unpackKey()
// undoes it.
uint64_t packKey(uint64_t x, uint64_t y, uint64_t z) { return (z << 32) | (y << 16) | x; }
uint64_t packKey(const octomap::OcTreeKey& k) { return packKey(k[0], k[1], k[2]); }

octomap::OcTreeKey unpackKey(uint64_t p) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(p & 0xffff),
                            static_cast<octomap::key_type>((p >> 16) & 0xffff),
                            static_cast<octomap::key_type>(p >> 32));
}

// finalizeRecurs() over the parts of the tree an insertion touched. The tree is split into
// regions, the subtrees of the nodes at kRegionDepth (32 voxels a side: 1.6 m at 5 cm); a
// region none of whose voxels was updated since the last pass is unchanged (nodes change
// only by updates, which mark their region, and by pruning, which happens only in these
// passes), so its counts are taken from the last pass instead of walking it. Above the
// regions every node is visited as in finalizeRecurs(). A region's cached counts are used
// only for the very node they were counted on; any other node there (e.g. re-created when a
// pruned ancestor was expanded for a neighbour's update) is counted afresh.
class IncrementalFinalizer {
 public:
  static constexpr unsigned kRegionDepth = 11;

  void markDirty(const octomap::OcTreeKey& k) {
    const unsigned shift = 16 - kRegionDepth;  // OcTree keys have 16 levels
    const uint64_t r = packKey(k[0] >> shift, k[1] >> shift, k[2] >> shift);
    if (r == last_marked_) return;
    last_marked_ = r;
    dirty_.insert(r);
  }
  // Updates whose keys were not marked (OctoMap's own insertion): walk everything next time.
  void markAllDirty() { all_dirty_ = true; }

  LeafCounts run(octomap::OcTree& tree) {
    LeafCounts c;
    if (tree.getRoot() != nullptr) recurs(tree, tree.getRoot(), 0, 0, 0, 0, &c);
    dirty_.clear();
    last_marked_ = kNone;
    all_dirty_ = false;
    return c;
  }

 private:
  static constexpr uint64_t kNone = ~uint64_t{0};
  static void add(LeafCounts* to, const LeafCounts& c) {
    to->occupied_voxels += c.occupied_voxels;
    to->free_voxels += c.free_voxels;
    to->leaves += c.leaves;
  }

  // x, y, z: the node's key prefix (depth bits per axis).
  void recurs(octomap::OcTree& tree, octomap::OcTreeNode* node, unsigned depth, uint64_t x,
              uint64_t y, uint64_t z, LeafCounts* c) {
    if (depth == kRegionDepth) {
      const uint64_t r = packKey(x, y, z);
      if (!all_dirty_ && dirty_.count(r) == 0) {
        const auto it = cache_.find(r);
        if (it != cache_.end() && it->second.node == node) return add(c, it->second.counts);
      }
      LeafCounts sub;
      finalizeRecurs(tree, node, depth, &sub);
      cache_[r] = {node, sub};
      return add(c, sub);
    }
    if (!tree.nodeHasChildren(node)) return countLeaf(tree, node, depth, c);
    for (unsigned i = 0; i < 8; ++i) {
      if (tree.nodeChildExists(node, i)) {
        // Child i sets key bit (15 - depth) of x, y, z to bits 0, 1, 2 of i.
        recurs(tree, tree.getNodeChild(node, i), depth + 1, (x << 1) | (i & 1u),
               (y << 1) | ((i >> 1) & 1u), (z << 1) | ((i >> 2) & 1u), c);
      }
    }
    if (depth > 0 && tree.pruneNode(node)) {
      c->leaves -= 7;
      return;
    }
    node->updateOccupancyChildren();
  }

  struct Cached {
    const octomap::OcTreeNode* node;
    LeafCounts counts;
  };
  std::unordered_set<uint64_t> dirty_;
  std::unordered_map<uint64_t, Cached> cache_;
  uint64_t last_marked_ = kNone;
  bool all_dirty_ = true;
};

// Which full-depth voxels are occupied, kept beside the tree as the insertion updates it, and
// each one's state at the last take(). OctoMap's own change detection notes every new leaf (a
// sweep's millions of new free voxels) in a hash map; here a leaf update costs a hash operation
// only when it can change the voxel's occupancy: a hit, or a miss that leaves the voxel's
// log-odds in [log-odds(prob_miss), 0), the only values a miss reaches from an occupied voxel
// (>= 0) or from a new one (0, i.e. unknown before). A miss that leaves it >= 0 left it occupied,
// one below that found it free already (or clamped, unchanged).
class ChangeTracker {
 public:
  bool on() const { return on_; }
  void start(std::vector<uint64_t> occupied) {
    on_ = true;
    occupied_ = std::unordered_set<uint64_t>(occupied.begin(), occupied.end());
    before_.clear();
  }
  void afterHit(const octomap::OcTree& tree, const octomap::OcTreeKey& k,
                const octomap::OcTreeNode* leaf) {
    if (on_ && leaf != nullptr) set(packKey(k), tree.isNodeOccupied(leaf));
  }
  void afterMiss(const octomap::OcTree& tree, const octomap::OcTreeKey& k,
                 const octomap::OcTreeNode* leaf) {
    if (!on_ || leaf == nullptr) return;
    const float l = leaf->getLogOdds();
    if (l < tree.getOccupancyThresLog() && l >= tree.getProbMissLog()) set(packKey(k), false);
  }
  // Brings the set to `occupied` (after an insertion whose updates were not seen).
  void resync(const std::vector<uint64_t>& occupied) {
    const std::unordered_set<uint64_t> now(occupied.begin(), occupied.end());
    std::vector<uint64_t> gone;
    for (const uint64_t k : occupied_) {
      if (!now.count(k)) gone.push_back(k);
    }
    for (const uint64_t k : gone) set(k, false);
    for (const uint64_t k : occupied) set(k, true);
  }
  const std::unordered_set<uint64_t>& occupied() const { return occupied_; }
  // The keys whose state differs from the last take(), as (key, occupied now); then forgets.
  std::vector<std::pair<uint64_t, bool>> take() {
    std::vector<std::pair<uint64_t, bool>> out;
    for (const auto& [k, was] : before_) {
      const bool now = occupied_.count(k) > 0;
      if (now != was) out.emplace_back(k, now);
    }
    before_.clear();
    return out;
  }

 private:
  void set(uint64_t k, bool occupied) {
    const bool was = occupied_.count(k) > 0;
    if (was == occupied) return;
    before_.emplace(k, was);  // the first change since the last take keeps its state then
    if (occupied) {
      occupied_.insert(k);
    } else {
      occupied_.erase(k);
    }
  }
  bool on_ = false;
  std::unordered_set<uint64_t> occupied_;
  std::unordered_map<uint64_t, bool> before_;
};

// octomap's discretized insertion (computeDiscreteUpdate + computeUpdate), with the ray
// keys collected in a bitmap over the sweep's key box instead of a hash set: the same
// voxels get the same single update, about twice as fast.
void insertDiscretized(octomap::OcTree& tree, double max_range, const octomap::Pointcloud& cloud,
                       const octomap::point3d& origin, IncrementalFinalizer* touched,
                       ChangeTracker* changes) {
  octomap::OcTreeKey origin_key;
  if (!tree.coordToKeyChecked(origin, origin_key)) {
    throw std::invalid_argument("OccupancyMap::insertCloud: sensor origin outside the map");
  }
  // Distinct endpoint voxels, in key order.
  std::vector<uint64_t> packed;
  packed.reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    octomap::OcTreeKey k;
    if (!tree.coordToKeyChecked(cloud[i], k)) continue;
    packed.push_back(packKey(k));
  }
  std::sort(packed.begin(), packed.end());
  packed.erase(std::unique(packed.begin(), packed.end()), packed.end());
  // Ray ends (range-limited) first, then the key box they and the origin span: the bitmaps
  // cover only what this cloud touches.
  struct RayEnd {
    octomap::point3d end;
    bool occupied;
    octomap::OcTreeKey key;
  };
  std::vector<RayEnd> ends;
  ends.reserve(packed.size());
  octomap::OcTreeKey lo = origin_key, hi = origin_key;
  for (const uint64_t p : packed) {
    const octomap::OcTreeKey k = unpackKey(p);
    octomap::point3d end = tree.keyToCoord(k);
    const double dist = (end - origin).norm();
    const bool occupied = dist <= max_range;
    if (!occupied) end = origin + (end - origin) * static_cast<float>(max_range / dist);
    octomap::OcTreeKey end_key;
    if (!tree.coordToKeyChecked(end, end_key)) continue;
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], end_key[i]);
      hi[i] = std::max(hi[i], end_key[i]);
    }
    ends.push_back({end, occupied, k});
  }
  KeyBitmap free_bits(lo, hi);
  std::vector<octomap::OcTreeKey> occupied;
  occupied.reserve(ends.size());
  for (const RayEnd& e : ends) {
    markRay(tree, origin, e.end, &free_bits);
    if (e.occupied) occupied.push_back(e.key);
  }
  KeyBitmap occupied_bits(lo, hi);
  for (const auto& k : occupied) occupied_bits.set(k);
  free_bits.forEach([&](const octomap::OcTreeKey& k) {
    if (!occupied_bits.test(k)) {
      touched->markDirty(k);
      changes->afterMiss(tree, k, tree.updateNode(k, false, /*lazy_eval=*/true));
    }
  });
  for (const auto& k : occupied) {
    touched->markDirty(k);
    changes->afterHit(tree, k, tree.updateNode(k, true, /*lazy_eval=*/true));
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

  // Leaf updates of one cloud (lazy: inner nodes stale until finalize()).
  void castCloud(const std::vector<Eigen::Vector3f>& points_m, const octomap::point3d& origin,
                 InsertMode mode);
  bool originInside(const Eigen::Vector3f& origin_m) const;
  void finalize();  // inner occupancy and pruning of the whole tree, then the stats
  MapStats statsFrom(const LeafCounts& counts) const;
  MapStats cached_stats;
  bool stats_valid = false;
  IncrementalFinalizer finalizer;
  ChangeTracker changes;
  // The packed keys of every occupied full-depth voxel, from the tree.
  std::vector<uint64_t> occupiedKeys() const;
};

OccupancyMap::OccupancyMap(const MapperConfig& config)
    : impl_((validate(config), std::make_unique<Impl>(config))) {}
OccupancyMap::OccupancyMap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

void OccupancyMap::Impl::castCloud(const std::vector<Eigen::Vector3f>& points_m,
                                   const octomap::point3d& origin, InsertMode mode) {
  octomap::Pointcloud& cloud = scratch;
  cloud.clear();
  cloud.reserve(points_m.size());
  for (const Eigen::Vector3f& p : points_m) {
    if (!p.allFinite()) {
      ++skipped;
      continue;
    }
    cloud.push_back(p.x(), p.y(), p.z());
  }

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
  //
  // Lazy evaluation: the leaves are updated first and the inner nodes once afterwards
  // (then pruned, see finalize()), instead of after every leaf update; the same tree,
  // about 1.4x faster.
  if (mode == InsertMode::kDiscretized) {
    insertDiscretized(tree, config.max_range_m, cloud, origin, &finalizer, &changes);
  } else {
    finalizer.markAllDirty();
    tree.insertPointCloud(cloud, origin, config.max_range_m, /*lazy_eval=*/true,
                          mode == InsertMode::kOctomapDiscretized);
    if (changes.on()) changes.resync(occupiedKeys());  // its updates were not seen
  }
  points += static_cast<int64_t>(cloud.size());
  ++sweeps;
}

bool OccupancyMap::Impl::originInside(const Eigen::Vector3f& origin_m) const {
  octomap::OcTreeKey key;
  return origin_m.allFinite() &&
         tree.coordToKeyChecked(octomap::point3d(origin_m.x(), origin_m.y(), origin_m.z()), key);
}

void OccupancyMap::Impl::finalize() {
  cached_stats = statsFrom(finalizer.run(tree));
  stats_valid = true;
}

MapStats OccupancyMap::Impl::statsFrom(const LeafCounts& counts) const {
  MapStats s;
  s.sweeps_inserted = sweeps;
  s.points_inserted = points;
  s.resolution_m = tree.getResolution();
  s.occupied_voxels = counts.occupied_voxels;
  s.free_voxels = counts.free_voxels;
  // OcTreeBaseImpl::memoryUsage(), with the leaf count of the same pass.
  using Base = octomap::OcTreeBaseImpl<octomap::OcTreeNode, octomap::AbstractOccupancyOcTree>;
  const size_t inner = tree.size() - static_cast<size_t>(counts.leaves);
  s.memory_bytes = static_cast<int64_t>(sizeof(Base) + tree.memoryUsageNode() * tree.size() +
                                        inner * sizeof(octomap::OcTreeNode* [8]));
  return s;
}

void OccupancyMap::insertCloud(const std::vector<Eigen::Vector3f>& points_m,
                               const Eigen::Vector3f& sensor_origin_m, InsertMode mode) {
  if (!sensor_origin_m.allFinite()) {
    throw std::invalid_argument("OccupancyMap::insertCloud: non-finite sensor origin");
  }
  if (!impl_->originInside(sensor_origin_m)) {
    throw std::invalid_argument("OccupancyMap::insertCloud: sensor origin outside the map");
  }
  impl_->castCloud(points_m,
                   octomap::point3d(sensor_origin_m.x(), sensor_origin_m.y(), sensor_origin_m.z()),
                   mode);
  impl_->finalize();
}

void OccupancyMap::insertClouds(const std::vector<SensorCloud>& clouds,
                                std::vector<size_t>* rejected) {
  bool any = false;
  for (size_t i = 0; i < clouds.size(); ++i) {
    const Eigen::Vector3f& o = clouds[i].origin_m;
    if (!impl_->originInside(o)) {
      if (rejected != nullptr) rejected->push_back(i);
      continue;
    }
    impl_->castCloud(clouds[i].points_m, octomap::point3d(o.x(), o.y(), o.z()),
                     InsertMode::kDiscretized);
    any = true;
  }
  if (any) impl_->finalize();
}

MapStats OccupancyMap::stats() const {
  if (impl_->stats_valid) return impl_->cached_stats;
  LeafCounts counts;
  if (impl_->tree.getRoot() != nullptr) countRecurs(impl_->tree, impl_->tree.getRoot(), 0, &counts);
  return impl_->statsFrom(counts);
}

std::vector<Eigen::Vector3f> OccupancyMap::occupiedCentres() const {
  const octomap::OcTree& tree = impl_->tree;
  std::vector<Eigen::Vector3f> out;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (tree.isNodeOccupied(*it)) out.emplace_back(it.getX(), it.getY(), it.getZ());
  }
  return out;
}

bool OccupancyMap::matchesOctomapReference() const {
  const octomap::OcTree& tree = impl_->tree;
  octomap::OcTree reference(tree);  // deep copy
  reference.updateInnerOccupancy();
  reference.prune();
  std::ostringstream ours(std::ios::binary), theirs(std::ios::binary);
  tree.write(ours);  // full .ot: structure and every node's log-odds, inner nodes included
  reference.write(theirs);
  if (ours.str() != theirs.str()) return false;
  MapStats s;
  const unsigned max_depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const int64_t voxels = int64_t{1} << (3 * (max_depth - it.getDepth()));
    (tree.isNodeOccupied(*it) ? s.occupied_voxels : s.free_voxels) += voxels;
  }
  const MapStats fast = stats();
  return fast.occupied_voxels == s.occupied_voxels && fast.free_voxels == s.free_voxels &&
         fast.memory_bytes == static_cast<int64_t>(tree.memoryUsage());
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

namespace {

// What OcTree::writeBinaryConst() writes (the .bt header, then the tree's binary data; like it,
// without pruning or modifying the tree, unlike writeBinary()), less the " done." that
// Debian 12's liboctomap prints on stderr after every write: the header is written here and
// only the data by the library, which prints nothing. A test checks the bytes are the same.
void writeBinaryQuietly(const octomap::OcTree& tree, std::ostream& s) {
  s << "# Octomap OcTree binary file\n"
       "# (feel free to add / change comments, but leave the first line as it is!)\n#\n";
  s << "id " << tree.getTreeType() << "\n";
  s << "size " << tree.size() << "\n";
  s << "res " << tree.getResolution() << "\n";
  s << "data\n";
  tree.writeBinaryData(s);
}

}  // namespace

void OccupancyMap::saveBinaryAtomic(const std::string& path) const {
  // Serialise in memory first (a room at 5 cm is a few MB), so that a failure leaves
  // neither a partial file nor a temporary one.
  std::ostringstream bytes(std::ios::binary);
  writeBinaryQuietly(impl_->tree, bytes);
  if (!bytes) throw std::runtime_error("cannot save " + path + ": OctoMap serialisation failed");
  writeFileAtomic(path, bytes.str());
}

namespace {

constexpr int32_t kKeyCentre = 32768;  // the key of index 0 (OcTree's tree_max_val, 16 levels)

VoxelIndex indexOf(const octomap::OcTreeKey& k) {
  return {int32_t{k[0]} - kKeyCentre, int32_t{k[1]} - kKeyCentre, int32_t{k[2]} - kKeyCentre};
}

}  // namespace

void OccupancyMap::trackChanges() {
  if (!impl_->changes.on()) impl_->changes.start(impl_->occupiedKeys());
}

VoxelChanges OccupancyMap::takeChanges() {
  VoxelChanges out;
  for (const auto& [packed, occupied] : impl_->changes.take()) {
    (occupied ? out.occupied : out.freed).push_back(indexOf(unpackKey(packed)));
  }
  std::sort(out.occupied.begin(), out.occupied.end());  // the hash map's order must not leak
  std::sort(out.freed.begin(), out.freed.end());
  return out;
}

std::vector<uint64_t> OccupancyMap::Impl::occupiedKeys() const {
  std::vector<uint64_t> out;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const int n = 1 << (tree.getTreeDepth() - it.getDepth());  // voxels a side
    const octomap::OcTreeKey key = it.getKey();
    uint64_t lo[3];
    for (int a = 0; a < 3; ++a) lo[a] = static_cast<uint64_t>(key[a] & ~(n - 1));
    for (uint64_t z = lo[2]; z < lo[2] + n; ++z) {
      for (uint64_t y = lo[1]; y < lo[1] + n; ++y) {
        for (uint64_t x = lo[0]; x < lo[0] + n; ++x) out.push_back(packKey(x, y, z));
      }
    }
  }
  return out;
}

std::vector<VoxelIndex> OccupancyMap::trackedVoxels() const {
  if (!impl_->changes.on()) return occupiedVoxels();
  std::vector<VoxelIndex> out;
  out.reserve(impl_->changes.occupied().size());
  for (const uint64_t k : impl_->changes.occupied()) out.push_back(indexOf(unpackKey(k)));
  std::sort(out.begin(), out.end());  // the hash set's order must not leak
  return out;
}

std::vector<VoxelIndex> OccupancyMap::occupiedVoxels() const {
  std::vector<VoxelIndex> out;
  for (const uint64_t k : impl_->occupiedKeys()) out.push_back(indexOf(unpackKey(k)));
  std::sort(out.begin(), out.end());
  return out;
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
