#include <pcl_fot/pcl/octree/octree_leaf_table.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>

#include <pcl/console/print.h>

#include <pcl_fot/detail/bits.h>
#include <pcl_fot/tree/accessor.h>

namespace pcl {
namespace fot {
namespace {

/** The deepest box the adapter follows PCL to: 2^29 cells per axis keeps tree keys in range. */
constexpr uindex_t kMaxPclDepth = 29;

/** What the walks' node array is made of: a leaf, or an empty old root (no slot), by its first voxel's key.
 */
struct WalkItem {
  std::uint32_t key[3];
  std::uint32_t level;
  OctreeLeafTable::Slot slot;
};

/** Morton order in PCL's child order (x above y above z at each depth); at one corner, bigger cubes first. */
bool mortonLess(const WalkItem& a, const WalkItem& b) {
  unsigned axis = 0;
  std::uint32_t top = a.key[0] ^ b.key[0];
  for (unsigned i = 1; i < 3; ++i) {
    // The axis whose keys differ in the highest bit decides; x wins a tie, then y.
    const std::uint32_t d = a.key[i] ^ b.key[i];
    if (top < d && top < (top ^ d)) axis = i, top = d;
  }
  return top != 0 ? a.key[axis] < b.key[axis] : a.level > b.level;
}

// A probe of the leaves' table is a cache miss (the table is much larger than the cache): batches of
// look-ups prefetch this many ahead, so that several misses are in flight at once.
constexpr std::size_t kProbesAhead = 8;

/**
 * The positions of `value` in ascending order, equal values in their order: a radix sort, least
 * significant digit first, of values below 2^bits.
 */
std::vector<std::uint32_t> radixOrder(std::vector<std::uint64_t> value, unsigned bits) {
  const std::size_t n = value.size();
  std::vector<std::uint32_t> order(n), scratch(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
  std::vector<std::uint64_t> value_scratch(n);
  constexpr unsigned kDigit = 11;  // 11 bits a pass; each pass is stable
  for (unsigned shift = 0; shift < bits; shift += kDigit) {
    std::vector<std::uint32_t> start((1u << kDigit) + 1, 0);
    for (std::size_t i = 0; i < n; ++i) ++start[(value[i] >> shift & ((1u << kDigit) - 1)) + 1];
    for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t at = start[value[i] >> shift & ((1u << kDigit) - 1)]++;
      value_scratch[at] = value[i];
      scratch[at] = order[i];
    }
    value.swap(value_scratch);
    order.swap(scratch);
  }
  return order;
}

/** PCL's index of the child holding the item's cube, in its node `level` + 1 levels above the voxels. */
unsigned childOf(const WalkItem& item, std::uint32_t level) {
  return (item.key[0] >> level & 1u) << 2 | (item.key[1] >> level & 1u) << 1 | (item.key[2] >> level & 1u);
}

/** Fills node `at` of the array, 2^level voxels a side, from its items [lo, hi), in Morton order. */
void fillNode(OctreeLeafTable::NodeArray& nodes, std::size_t at, const std::vector<WalkItem>& items,
              std::size_t lo, std::size_t hi, std::uint32_t level) {
  for (; lo < hi && items[lo].level == level; ++lo)
    if (items[lo].slot != OctreeLeafTable::kNoLeaf) {
      nodes[at] = OctreeLeafTable::FlatNode{items[lo].slot, 0, true};
      return;
    }  // else an empty old root, which PCL keeps as a branch over whatever lies below it
  std::uint8_t children = 0;
  for (std::size_t i = lo; i < hi; ++i) children |= std::uint8_t(1u << childOf(items[i], level - 1));
  const std::uint32_t first = std::uint32_t(nodes.size());
  nodes[at] = OctreeLeafTable::FlatNode{first, children, false};
  nodes.resize(first + detail::popcount64(children));
  for (std::size_t i = lo, rank = 0; i < hi; ++rank) {
    const unsigned child = childOf(items[i], level - 1);
    std::size_t end = i;
    while (end < hi && childOf(items[end], level - 1) == child) ++end;
    fillNode(nodes, first + rank, items, i, end, level - 1);
    i = end;
  }
}

}  // namespace

std::size_t OctreeLeafTable::LeafIdHash::operator()(const LeafId& id) const {
  std::uint64_t h = std::uint64_t(std::uint32_t(id.corner.x)) * 0x9E3779B97F4A7C15ULL;
  h ^= (std::uint64_t(std::uint32_t(id.corner.y)) + (h << 6) + (h >> 2)) * 0xC2B2AE3D27D4EB4FULL;
  h ^= (std::uint64_t(std::uint32_t(id.corner.z)) ^ (std::uint64_t(id.level) << 40)) * 0x165667B19E3779F9ULL;
  return std::size_t(h ^ (h >> 29));
}

template <typename Value>
const Value* OctreeLeafTable::CubeMap<Value>::find(const LeafId& id) const {
  if (size_ == 0) return nullptr;
  for (std::size_t i = home(id);; i = (i + 1) & (entries_.size() - 1)) {
    const Entry& e = entries_[i];
    if (!e.used) return nullptr;
    if (e.id == id) return &e.value;
  }
}

template <typename Value>
Value& OctreeLeafTable::CubeMap<Value>::findOrAdd(const LeafId& id, bool& added) {
  if (2 * (size_ + 1) > entries_.size()) grow(std::max<std::size_t>(16, 2 * entries_.size()));
  std::size_t i = home(id);
  while (entries_[i].used && !(entries_[i].id == id)) i = (i + 1) & (entries_.size() - 1);
  added = !entries_[i].used;
  if (added) {
    entries_[i] = Entry{id, Value{}, true};
    ++size_;
  }
  return entries_[i].value;
}

template <typename Value>
bool OctreeLeafTable::CubeMap<Value>::erase(const LeafId& id) {
  if (size_ == 0) return false;
  const std::size_t mask = entries_.size() - 1;
  std::size_t i = home(id);
  while (entries_[i].used && !(entries_[i].id == id)) i = (i + 1) & mask;
  if (!entries_[i].used) return false;
  // Backward shift: an entry after the hole moves into it unless its home lies between the hole and it.
  for (std::size_t j = (i + 1) & mask; entries_[j].used; j = (j + 1) & mask) {
    const std::size_t h = home(entries_[j].id);
    if (((j - h) & mask) >= ((j - i) & mask)) {
      entries_[i] = entries_[j];
      i = j;
    }
  }
  entries_[i] = Entry{};
  --size_;
  return true;
}

template <typename Value>
void OctreeLeafTable::CubeMap<Value>::clear() {
  entries_.clear();
  size_ = 0;
}

template <typename Value>
void OctreeLeafTable::CubeMap<Value>::reserve(std::size_t n) {
  std::size_t capacity = 16;
  while (capacity < 2 * n) capacity *= 2;
  if (capacity > entries_.size()) grow(capacity);
}

template <typename Value>
void OctreeLeafTable::CubeMap<Value>::grow(std::size_t capacity) {
  std::vector<Entry> old(capacity);
  old.swap(entries_);
  size_ = 0;
  bool added;
  for (const Entry& e : old)
    if (e.used) findOrAdd(e.id, added) = e.value;
}

template class OctreeLeafTable::CubeMap<OctreeLeafTable::Slot>;
template class OctreeLeafTable::CubeMap<std::uint8_t>;

OctreeLeafTable::OctreeLeafTable(double resolution, bool holds_leaves)
    : resolution_(resolution), holds_leaves_(holds_leaves), tree_(resolution) {
  max_[0] = max_[1] = max_[2] = resolution;
}

bool OctreeLeafTable::setResolution(double resolution) {
  if (leafCount() != 0) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::setResolution] The octree must be empty to change its resolution.\n");
    return false;
  }
  const std::string why = CellGrid::whyInvalid(resolution, 0.0, 0.0, 0.0);
  if (!why.empty()) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::setResolution] Refused: %s.\n", why.c_str());
    return false;
  }
  resolution_ = resolution;
  tree_ = FastOctTree(resolution);
  getKeyBitSize();
  ++version_;
  return true;
}

void OctreeLeafTable::getBoundingBox(double min[3], double max[3]) const {
  std::copy(min_, min_ + 3, min);
  std::copy(max_, max_ + 3, max);
}

octree::OctreeKey OctreeLeafTable::pclKey(double x, double y, double z) const {
  // A point just inside the box's far face can round to one voxel past it; pcl::octree asserts there.
  const uindex_t last = static_cast<uindex_t>((std::uint64_t(1) << depth_) - 1);
  return octree::OctreeKey(std::min(static_cast<uindex_t>((x - min_[0]) / resolution_), last),
                           std::min(static_cast<uindex_t>((y - min_[1]) / resolution_), last),
                           std::min(static_cast<uindex_t>((z - min_[2]) / resolution_), last));
}

void OctreeLeafTable::voxelCenter(const octree::OctreeKey& key, uindex_t depth, double center[3]) const {
  const double side = resolution_ * static_cast<double>(std::uint64_t(1) << (depth_ - depth));
  const uindex_t k[3] = {key.x, key.y, key.z};
  for (int a = 0; a < 3; ++a) center[a] = (static_cast<double>(k[a]) + 0.5f) * side + min_[a];
}

double OctreeLeafTable::voxelSquaredSideLen(uindex_t depth) const {
  const double side = std::ldexp(resolution_, int(depth_) - int(depth));
  return side * side;
}

void OctreeLeafTable::voxelBounds(const octree::OctreeKey& key, uindex_t depth, Eigen::Vector3f& min_pt,
                                  Eigen::Vector3f& max_pt) const {
  const double side = std::ldexp(resolution_, int(depth_) - int(depth));
  const uindex_t k[3] = {key.x, key.y, key.z};
  for (int a = 0; a < 3; ++a) {
    min_pt(a) = static_cast<float>(static_cast<double>(k[a]) * side + min_[a]);
    max_pt(a) = static_cast<float>(static_cast<double>(k[a] + 1) * side + min_[a]);
  }
}

bool OctreeLeafTable::setTreeDepth(uindex_t depth) {
  if (depth == 0 || depth > kMaxPclDepth) {
    PCL_ERROR("[pcl::fot::OctreePointCloud] Refused tree depth %u: it must be 1 to %u.\n", depth,
              kMaxPclDepth);
    return false;
  }
  if (bounding_box_defined_) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud] Refused tree depth %u: the bounding box, defined already, sets the "
        "depth.\n",
        depth);
    return false;
  }
  depth_ = depth;
  ++version_;
  return true;
}

void OctreeLeafTable::getKeyBitSize() {
  // PCL's arithmetic, step for step, so that the box comes out bit for bit the same.
  const float min_value = std::numeric_limits<float>::epsilon();
  uindex_t max_voxels = 2;
  for (int a = 0; a < 3; ++a)
    max_voxels =
        std::max(max_voxels, static_cast<uindex_t>(std::ceil((max_[a] - min_[a] - min_value) / resolution_)));
  depth_ = std::max<uindex_t>(
      std::min<uindex_t>(octree::OctreeKey::maxDepth, std::ceil(std::log2(max_voxels) - min_value)), 0);
  const double side = static_cast<double>(std::uint64_t(1) << depth_) * resolution_;
  for (int a = 0; a < 3; ++a) {
    if (leafCount() == 0) {
      const double oversize = (side - (max_[a] - min_[a])) / 2.0;
      if (oversize > min_value) {
        min_[a] -= oversize;
        max_[a] += oversize;
      }
    } else {
      max_[a] = min_[a] + side;
    }
  }
}

bool OctreeLeafTable::adoptBoundingBoxToPoint(double x, double y, double z) {
  const float min_value = std::numeric_limits<float>::epsilon();
  const double p[3] = {x, y, z};
  // A point that does not fit leaves the box as it was, not grown part of the way.
  const auto box = std::make_tuple(std::array<double, 3>{min_[0], min_[1], min_[2]},
                                   std::array<double, 3>{max_[0], max_[1], max_[2]}, depth_, offset_);
  const std::size_t phantoms = phantoms_.size();
  while (true) {
    bool lower[3], upper[3];
    for (int a = 0; a < 3; ++a) {
      lower[a] = p[a] < min_[a];
      upper[a] = p[a] >= max_[a];
    }
    const bool violated = lower[0] || lower[1] || lower[2] || upper[0] || upper[1] || upper[2];
    if (bounding_box_defined_ && !violated) return true;
    ++version_;  // a new box: keys, root and branches change
    if (!bounding_box_defined_) {
      // The first point: a box of ±res/2 around it.
      for (int a = 0; a < 3; ++a) {
        min_[a] = p[a] - resolution_ / 2;
        max_[a] = p[a] + resolution_ / 2;
      }
      getKeyBitSize();
      offset_ = {0, 0, 0};
      phantoms_.clear();
      bounding_box_defined_ = true;
      continue;
    }
    if (depth_ >= kMaxPclDepth) {
      PCL_ERROR(
          "[pcl::fot::OctreePointCloud] The point (%g, %g, %g) would grow the octree beyond 2^%u cells per "
          "axis; it is not added.\n",
          x, y, z, kMaxPclDepth);
      const auto& [lo, hi, depth, offset] = box;
      std::copy(lo.begin(), lo.end(), min_);
      std::copy(hi.begin(), hi.end(), max_);
      depth_ = depth;
      offset_ = offset;
      phantoms_.resize(phantoms);
      return false;
    }
    // A new root: the box doubles, downwards on every axis the point does not exceed upwards.
    if (leafCount() == 0)  // PCL keeps the empty old root as a branch
      phantoms_.push_back({Key{offset_[0], offset_[1], offset_[2]}, depth_});
    const double side = static_cast<double>(std::uint64_t(1) << depth_) * resolution_;
    for (int a = 0; a < 3; ++a)
      if (!upper[a]) {
        min_[a] -= side;
        offset_[a] -= std::int32_t(1) << depth_;
      }
    ++depth_;
    const double new_side = static_cast<double>(std::uint64_t(1) << depth_) * resolution_ - min_value;
    for (int a = 0; a < 3; ++a) max_[a] = min_[a] + new_side;
  }
}

void OctreeLeafTable::defineBoundingBox(const double min[3], const double max[3]) {
  if (leafCount() != 0) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::defineBoundingBox] The octree must be empty to define its box.\n");
    return;
  }
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(min[a]) || !std::isfinite(max[a])) {
      PCL_ERROR("[pcl::fot::OctreePointCloud::defineBoundingBox] The box must be finite.\n");
      return;
    }
  const double saved_min[3] = {min_[0], min_[1], min_[2]}, saved_max[3] = {max_[0], max_[1], max_[2]};
  const uindex_t saved_depth = depth_;
  for (int a = 0; a < 3; ++a) {
    min_[a] = std::min(min[a], max[a]);
    max_[a] = std::max(min[a], max[a]);
  }
  getKeyBitSize();
  if (depth_ > kMaxPclDepth) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::defineBoundingBox] The box spans more than 2^%u cells per axis.\n",
        kMaxPclDepth);
    std::copy(saved_min, saved_min + 3, min_);
    std::copy(saved_max, saved_max + 3, max_);
    depth_ = saved_depth;
    return;
  }
  offset_ = {0, 0, 0};
  phantoms_.clear();
  bounding_box_defined_ = true;
  ++version_;
}

void OctreeLeafTable::enableDynamicDepth(std::size_t max_objs_per_leaf) {
  if (leafCount() != 0) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::enableDynamicDepth] The octree must be empty.\n");
    return;
  }
  max_objs_per_leaf_ = max_objs_per_leaf;
}

OctreeLeafTable::LeafId OctreeLeafTable::cubeOf(const Key& k, std::uint32_t level) const {
  const auto align = [&](std::int32_t v, std::int32_t offset) {
    return std::int32_t(((std::uint32_t(v - offset) >> level) << level) + std::uint32_t(offset));
  };
  return LeafId{Key{align(k.x, offset_[0]), align(k.y, offset_[1]), align(k.z, offset_[2])}, level};
}

bool OctreeLeafTable::cubeHasContent(const LeafId& cube) const {
  const std::int32_t last = std::int32_t((std::int64_t(1) << cube.level) - 1);
  const Key hi{cube.corner.x + last, cube.corner.y + last, cube.corner.z + last};
  for (const Phantom& ph : phantoms_)
    if (ph.level <= cube.level && ph.min.x >= cube.corner.x && ph.min.x <= hi.x &&
        ph.min.y >= cube.corner.y && ph.min.y <= hi.y && ph.min.z >= cube.corner.z && ph.min.z <= hi.z)
      return true;
  bool occupied = false;
  tree_.forEachRegionInBox(cube.corner, hi, [&](const Region& r) {
    occupied = r.state == CellState::Occupied;
    return !occupied;
  });
  return occupied;
}

OctreeLeafTable::Slot OctreeLeafTable::leafOnPath(const Key& k, LeafId& id) const {
  if (max_objs_per_leaf_ == 0) {
    id = LeafId{k, 0};
    return leafOf(id);
  }
  // PCL's descent: the root is a branch; below it, the first leaf, or the first node missing.
  for (std::uint32_t level = depth_ - 1;; --level) {
    id = cubeOf(k, level);
    const Slot slot = leafOf(id);
    if (slot != kNoLeaf) return slot;
    if (level == 0 || !cubeHasContent(id)) return kNoLeaf;
  }
}

OctreeLeafTable::Slot OctreeLeafTable::takeSlot() {
  if (free_slots_.empty()) return next_slot_++;
  const Slot slot = free_slots_.back();
  free_slots_.pop_back();
  return slot;
}

OctreeLeafTable::Slot OctreeLeafTable::addLeaf(const LeafId& id) {
  const Slot slot = takeSlot();
  bool added;
  leaves_.findOrAdd(id, added) = slot;
  return slot;
}

std::vector<std::uint32_t> OctreeLeafTable::cellOrder(const std::vector<Key>& keys) {
  const std::size_t n = keys.size();
  if (n < 2) return std::vector<std::uint32_t>(n, 0);
  // Each key as one number: its offsets from the lowest key on each axis, side by side.
  std::int64_t lo[3] = {keys[0].x, keys[0].y, keys[0].z}, hi[3] = {lo[0], lo[1], lo[2]};
  for (const Key& k : keys) {
    const std::int64_t c[3] = {k.x, k.y, k.z};
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
  }
  unsigned bits = 0;
  for (int a = 0; a < 3; ++a)
    while ((hi[a] - lo[a]) >> bits != 0) ++bits;
  const auto packed = [&](const Key& k) {
    return std::uint64_t(k.x - lo[0]) << (2 * bits) | std::uint64_t(k.y - lo[1]) << bits |
           std::uint64_t(k.z - lo[2]);
  };
  if (3 * bits > 64) {  // the box spans more than 2^21 cells: a comparison sort
    std::vector<std::uint32_t> order(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return std::tie(keys[a].x, keys[a].y, keys[a].z) < std::tie(keys[b].x, keys[b].y, keys[b].z);
    });
    return order;
  }
  std::vector<std::uint64_t> value(n);
  for (std::size_t i = 0; i < n; ++i) value[i] = packed(keys[i]);
  return radixOrder(std::move(value), 3 * bits);
}

OctreeLeafTable::Slot OctreeLeafTable::leafForPoint(const Key& k, LeafId& id, bool& created) {
  const std::uint64_t before = version_++;
  created = false;
  Slot slot = kNoLeaf;
  bool new_node = false;  // a leaf or, without containers, a cell: the branches gain it
  if (!holds_leaves_) {
    new_node = tree_.getCell(k) != CellState::Occupied;
    tree_.setCell(k, CellState::Occupied);
    id = LeafId{k, 0};
    slot = 0;
  } else if (max_objs_per_leaf_ == 0) {
    id = LeafId{k, 0};
    if (last_slot_ != kNoLeaf && last_id_ == id) {
      slot = last_slot_;
    } else {
      bool added;
      Slot& entry = leaves_.findOrAdd(id, added);
      if (added) {
        entry = takeSlot();
        created = new_node = true;
        tree_.setCell(k, CellState::Occupied);
      }
      slot = entry;
      last_id_ = id;
      last_slot_ = slot;
    }
  } else {
    slot = leafOnPath(k, id);
    if (slot == kNoLeaf) {
      slot = addLeaf(id);
      created = new_node = true;
    }
  }
  // The branch index follows a new leaf in place: adding a point and then searching approximately or
  // counting branches again costs what the change costs. Walks build their node array anew.
  branch_cache_.follow(before, version_, [&](BranchIndex& index) {
    if (new_node) addToBranches(index, id);
  });
  return slot;
}

void OctreeLeafTable::leavesOfCells(const std::vector<Key>& cells, std::vector<Slot>& slots,
                                    std::vector<bool>& created) {
  slots.resize(cells.size());
  created.assign(cells.size(), false);
  if (cells.empty()) return;
  const std::uint64_t before = version_++;
  leaves_.reserve(leaves_.size() + cells.size());
  std::vector<Key> fresh;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i + kProbesAhead < cells.size()) leaves_.prefetch(LeafId{cells[i + kProbesAhead], 0});
    bool added;
    Slot& entry = leaves_.findOrAdd(LeafId{cells[i], 0}, added);
    if (added) {
      entry = takeSlot();
      fresh.push_back(cells[i]);
    }
    slots[i] = entry;
    created[i] = added;
  }
  tree_.insertKeys(fresh.data(), fresh.size(), CellState::Occupied);
  last_id_ = LeafId{cells.back(), 0};
  last_slot_ = slots.back();
  branch_cache_.follow(before, version_, [&](BranchIndex& index) {
    for (const Key& k : fresh) addToBranches(index, LeafId{k, 0});
  });
}

OctreeLeafTable::Slot OctreeLeafTable::createLeaf(const octree::OctreeKey& key, bool& created) {
  const Key k = pclKeyToTreeKey(key);
  LeafId id;
  const Slot slot = leafForPoint(k, id, created);
  if (max_objs_per_leaf_ != 0) markCell(k);
  return slot;
}

OctreeLeafTable::Slot OctreeLeafTable::leafOfCube(const LeafId& id, bool& created) {
  const Slot slot = leafOf(id);
  created = slot == kNoLeaf;
  return created ? addLeaf(id) : slot;
}

void OctreeLeafTable::eraseLeaf(const LeafId& id) {
  const Slot slot = leafOf(id);
  if (!leaves_.erase(id)) return;
  ++version_;
  free_slots_.push_back(slot);
  if (last_slot_ == slot) last_slot_ = kNoLeaf;
}

OctreeLeafTable::Slot OctreeLeafTable::findLeaf(const octree::OctreeKey& key) const {
  if (!holds_leaves_) return leafAt(key, depth_);
  LeafId id;
  return leafOnPath(pclKeyToTreeKey(key), id);
}

void OctreeLeafTable::findLeaves(const std::vector<octree::OctreeKey>& keys, std::vector<Slot>& slots) const {
  slots.resize(keys.size());
  if (!holds_leaves_ || max_objs_per_leaf_ != 0) {
    for (std::size_t i = 0; i < keys.size(); ++i) slots[i] = findLeaf(keys[i]);
    return;
  }
  const auto id = [&](std::size_t i) { return LeafId{pclKeyToTreeKey(keys[i]), 0}; };
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (i + kProbesAhead < keys.size()) leaves_.prefetch(id(i + kProbesAhead));
    slots[i] = leafOf(id(i));
  }
}

OctreeLeafTable::Slot OctreeLeafTable::leafAt(const octree::OctreeKey& key, uindex_t depth) const {
  const std::uint32_t level = depth_ - depth;
  const Key corner = pclKeyToTreeKey(firstVoxel(key, level));
  if (!holds_leaves_)  // the occupancy octree's leaves are its cells
    return level == 0 && tree_.getCell(corner) == CellState::Occupied ? 0 : kNoLeaf;
  return leafOf(LeafId{corner, level});
}

bool OctreeLeafTable::existLeaf(uindex_t x, uindex_t y, uindex_t z) const {
  if (((x | y | z) >> depth_) != 0) return false;
  return findLeaf(octree::OctreeKey(x, y, z)) != kNoLeaf;
}

OctreeLeafTable::Slot OctreeLeafTable::removeLeaf(uindex_t x, uindex_t y, uindex_t z) {
  if (((x | y | z) >> depth_) != 0) return kNoLeaf;
  const Key target = pclKeyToTreeKey(octree::OctreeKey(x, y, z));
  const std::uint64_t before = version_++;
  LeafId gone{target, 0};
  Slot slot = kNoLeaf;
  bool removed = false;
  if (holds_leaves_) {
    // The first leaf on the path goes, with every cell of its cube.
    slot = leafOnPath(target, gone);
    if (slot != kNoLeaf) {
      const std::int32_t last = std::int32_t((std::int64_t(1) << gone.level) - 1);
      eraseLeaf(gone);
      tree_.setBox(gone.corner, Key{gone.corner.x + last, gone.corner.y + last, gone.corner.z + last},
                   CellState::Unknown);
      removed = true;
    }
  } else {
    removed = tree_.getCell(target) == CellState::Occupied;
    tree_.eraseCell(target);
  }
  // The branch index follows, unless empty old roots are about: their pruning below is left to a new
  // index.
  if (phantoms_.empty())
    branch_cache_.follow(before, version_, [&](BranchIndex& index) {
      if (removed) removeFromBranches(index, gone);
    });
  // PCL prunes the branches left without children on the way to the deleted voxel. Empty old roots nest,
  // so the smallest goes first, and each larger one only once nothing is left inside it.
  std::sort(phantoms_.begin(), phantoms_.end(),
            [](const Phantom& a, const Phantom& b) { return a.level < b.level; });
  while (!phantoms_.empty()) {
    const Phantom& ph = phantoms_.front();
    const std::int32_t last = std::int32_t((std::int64_t(1) << ph.level) - 1);
    const Key hi{ph.min.x + last, ph.min.y + last, ph.min.z + last};
    const bool on_path = target.x >= ph.min.x && target.x <= hi.x && target.y >= ph.min.y &&
                         target.y <= hi.y && target.z >= ph.min.z && target.z <= hi.z;
    bool holds_voxels = false;
    if (on_path)
      tree_.forEachRegionInBox(ph.min, hi, [&](const Region& r) {
        holds_voxels = r.state == CellState::Occupied;
        return !holds_voxels;
      });
    if (!on_path || holds_voxels) break;
    phantoms_.erase(phantoms_.begin());
  }
  return slot;
}

void OctreeLeafTable::clearLeaves() {
  tree_.clear();
  leaves_.clear();
  free_slots_.clear();
  next_slot_ = 0;
  last_slot_ = kNoLeaf;
  phantoms_.clear();
  ++version_;
}

void OctreeLeafTable::clear() {
  min_[0] = min_[1] = min_[2] = max_[0] = max_[1] = max_[2] = 0;
  bounding_box_defined_ = false;
  clearLeaves();
}

std::shared_ptr<const OctreeLeafTable::BranchIndex> OctreeLeafTable::branchIndex() const {
  return branch_cache_.get(version_, [&] { return buildBranchIndex(); });
}

unsigned OctreeLeafTable::childIndex(const LeafId& node) const {
  const auto bit = [&](std::int32_t v, std::int32_t offset) {
    return (std::uint32_t(v - offset) >> node.level) & 1u;
  };
  return bit(node.corner.x, offset_[0]) << 2 | bit(node.corner.y, offset_[1]) << 1 |
         bit(node.corner.z, offset_[2]);
}

void OctreeLeafTable::addToBranches(BranchIndex& index, LeafId node) const {
  // Each node marks itself in its parent; a parent met before already has its ancestors marked.
  for (std::uint32_t level = node.level + 1; level <= depth_; ++level) {
    const LeafId parent = cubeOf(node.corner, level);
    const unsigned child = childIndex(node);
    bool added;
    std::uint8_t& children = index.findOrAdd(parent, added);
    children |= std::uint8_t(1u << child);
    if (!added) return;
    node = parent;
  }
}

void OctreeLeafTable::removeFromBranches(BranchIndex& index, LeafId node) const {
  // PCL's pruning: a parent left without children goes too, up to the root, which stays.
  for (std::uint32_t level = node.level + 1; level <= depth_; ++level) {
    const LeafId parent = cubeOf(node.corner, level);
    const unsigned child = childIndex(node);
    std::uint8_t* children = index.find(parent);
    if (!children) return;
    *children &= std::uint8_t(~(1u << child));
    if (*children != 0 || level == depth_) return;
    index.erase(parent);
    node = parent;
  }
}

std::shared_ptr<OctreeLeafTable::BranchIndex> OctreeLeafTable::buildBranchIndex() const {
  auto index = std::make_shared<BranchIndex>();
  const LeafId root = cubeOf(pclKeyToTreeKey(octree::OctreeKey(0, 0, 0)), depth_);
  bool added;
  index->findOrAdd(root, added);
  if (holds_leaves_)
    leaves_.forEach([&](const LeafId& id, Slot) { addToBranches(*index, id); });
  else
    tree_.forEachCell(CellState::Occupied, [&](const Key& k) { addToBranches(*index, LeafId{k, 0}); });
  // PCL keeps the empty old roots of a box grown before any point as branches.
  for (const Phantom& ph : phantoms_) {
    const LeafId cube{ph.min, std::uint32_t(ph.level)};
    index->findOrAdd(cube, added);
    addToBranches(*index, cube);
  }
  return index;
}

std::shared_ptr<const OctreeLeafTable::NodeArray> OctreeLeafTable::nodeArray() const {
  return node_cache_.get(version_, [&] { return buildNodeArray(); });
}

std::shared_ptr<OctreeLeafTable::NodeArray> OctreeLeafTable::buildNodeArray() const {
  // The leaves sorted in Morton order, then split depth by depth: no look-up per node.
  std::vector<WalkItem> items;
  const auto add = [&](const Key& corner, std::uint32_t level, Slot slot) {
    items.push_back(WalkItem{{std::uint32_t(corner.x - offset_[0]), std::uint32_t(corner.y - offset_[1]),
                              std::uint32_t(corner.z - offset_[2])},
                             level,
                             slot});
  };
  if (holds_leaves_) {
    items.reserve(leaves_.size() + phantoms_.size());
    leaves_.forEach([&](const LeafId& id, Slot slot) { add(id.corner, id.level, slot); });
  } else {
    tree_.forEachCell(CellState::Occupied, [&](const Key& k) { add(k, 0, 0); });
  }
  // PCL keeps the empty old roots of a box grown before any point as branches.
  for (const Phantom& ph : phantoms_) add(ph.min, std::uint32_t(ph.level), kNoLeaf);
  std::uint32_t any = 0;  // the keys' bits
  for (const WalkItem& w : items) any |= w.key[0] | w.key[1] | w.key[2];
  unsigned bits = 0;
  while (any >> bits != 0) ++bits;
  if (3 * bits + 5 <= 64) {
    // Morton codes in PCL's child order with the level below them (bigger cubes first): one radix sort.
    std::vector<std::uint64_t> code(items.size());
    for (std::size_t i = 0; i < items.size(); ++i) {
      const WalkItem& w = items[i];
      code[i] = detail::morton3(w.key[2], w.key[1], w.key[0]) << 5 | (31u - w.level);
    }
    const std::vector<std::uint32_t> order = radixOrder(std::move(code), 3 * bits + 5);
    std::vector<WalkItem> sorted(items.size());
    for (std::size_t i = 0; i < order.size(); ++i) sorted[i] = items[order[i]];
    items.swap(sorted);
  } else {  // keys of more than 19 bits: a comparison sort (a lambda, not the function's address: it inlines)
    std::sort(items.begin(), items.end(),
              [](const WalkItem& a, const WalkItem& b) { return mortonLess(a, b); });
  }
  auto nodes = std::make_shared<NodeArray>(1);
  fillNode(*nodes, 0, items, 0, items.size(), depth_);
  return nodes;
}

OctreeLeafTable::Slot OctreeLeafTable::approxLeaf(const Eigen::Vector3f& point) const {
  const auto branches = branchIndex();
  octree::OctreeKey key(0, 0, 0);
  std::uint8_t children = *branches->find(cubeOf(pclKeyToTreeKey(key), depth_));  // the root is always there
  for (uindex_t depth = 1; depth <= depth_; ++depth) {
    double nearest = std::numeric_limits<double>::max();
    octree::OctreeKey nearest_key;
    for (unsigned c = 0; c < 8; ++c) {
      if (!(children >> c & 1u)) continue;
      const octree::OctreeKey child = childKey(key, c);
      double center[3];
      voxelCenter(child, depth, center);
      const Eigen::Vector3f centre = Eigen::Vector3d(center[0], center[1], center[2]).cast<float>();
      const double d = (centre - point).squaredNorm();  // in float, as PCL
      if (d >= nearest) continue;
      nearest = d;
      nearest_key = child;
    }
    if (nearest == std::numeric_limits<double>::max()) return kNoLeaf;  // an empty old root: PCL asserts
    const std::uint32_t level = depth_ - depth;
    const std::uint8_t* branch =
        branches->find(LeafId{pclKeyToTreeKey(firstVoxel(nearest_key, level)), level});
    if (!branch) return leafAt(nearest_key, depth);
    key = nearest_key;
    children = *branch;
  }
  return kNoLeaf;
}

bool OctreeLeafTable::walkSegment(const Eigen::Vector3f& origin, const Eigen::Vector3f& end, float precision,
                                  const std::function<void(const octree::OctreeKey&)>& visit) const {
  // PCL's walk in small float steps; keys are only taken inside the box, where PCL's are defined.
  const float step_size = static_cast<float>(resolution_) * precision;
  if (!(end - origin).allFinite() || !(step_size > 0.0f) || !std::isfinite(step_size)) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::getApproxIntersectedVoxelCentersBySegment] The segment must "
        "be finite and the precision positive.\n");
    return false;
  }
  Eigen::Vector3f direction = end - origin;
  const float norm = direction.norm();
  direction.normalize();
  const double nsteps = std::max(1.0, std::floor(double(norm / step_size)));
  octree::OctreeKey prev_key;
  bool have_prev = false;
  auto add = [&](const Eigen::Vector3f& p) {
    if (!isPointWithinBoundingBox(p.x(), p.y(), p.z())) return;
    const octree::OctreeKey key = pclKey(p.x(), p.y(), p.z());
    if (have_prev && key == prev_key) return;
    prev_key = key;
    have_prev = true;
    visit(key);
  };
  // Only the steps near the part of the segment inside the box can add a voxel: a far end costs nothing.
  double t_in = 0.0, t_out = norm;
  for (int a = 0; a < 3; ++a) {
    const double o = origin[a], d = direction[a];
    if (d == 0.0) {
      if (o < min_[a] || o >= max_[a]) t_in = t_out + 1.0;
      continue;
    }
    double t0 = (min_[a] - o) / d, t1 = (max_[a] - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  if (bounding_box_defined_ && t_in <= t_out) {
    // A margin for the float rounding of the samples, which grows with their coordinates.
    const double slack = 2.0 + (double(norm) + origin.cwiseAbs().sum()) * 1e-6 / step_size;
    const double first = std::max(0.0, std::floor(t_in / step_size - slack));
    const double last = std::min(nsteps, std::ceil(t_out / step_size + slack));
    if (last - first > 0x1p32 || last > 0x1p53) {
      PCL_ERROR(
          "[pcl::fot::OctreePointCloud::getApproxIntersectedVoxelCentersBySegment] Refused: %g steps "
          "at this precision.\n",
          last - first);
      return false;
    }
    for (auto i = std::uint64_t(first); i < std::uint64_t(last); ++i)
      add(origin + (direction * step_size * static_cast<float>(i)));
  }
  add(end);
  return true;
}

void OctreeLeafTable::walkRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                              const std::function<bool(const octree::OctreeKey&)>& visit) const {
  const double norm = direction.cast<double>().norm();
  if (!bounding_box_defined_ || !(norm > 0.0) || !std::isfinite(norm) || !origin.allFinite()) return;
  // Clip the ray to the box (slab test), then walk its cells from the entry on.
  double t_in = 0.0, t_out = std::numeric_limits<double>::infinity();
  double dir[3];
  for (int a = 0; a < 3; ++a) {
    dir[a] = double(direction[a]) / norm;
    if (dir[a] == 0.0) {
      if (origin[a] < min_[a] || origin[a] >= max_[a]) return;
      continue;
    }
    double t0 = (min_[a] - origin[a]) / dir[a], t1 = (max_[a] - origin[a]) / dir[a];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  if (t_in >= t_out) return;
  const std::int64_t cells = std::int64_t(1) << depth_;
  std::int64_t k[3];
  int step[3];
  double rel[3];
  for (int a = 0; a < 3; ++a) {
    const double entry = origin[a] + t_in * dir[a];
    const double cell = std::floor((entry - min_[a]) / resolution_);
    k[a] = std::int64_t(std::min<double>(std::max<double>(cell, 0.0), double(cells - 1)));
    rel[a] = double(origin[a]) - min_[a];
    step[a] = dir[a] > 0.0 ? 1 : (dir[a] < 0.0 ? -1 : 0);
  }
  // Where the ray leaves cell j along axis a, computed from j and never accumulated: a jump over an empty
  // cube then lands in the cell that steps through it would reach.
  const auto leave = [&](int a, std::int64_t j) {
    return step[a] == 0 ? std::numeric_limits<double>::infinity()
                        : ((double(j) + (step[a] > 0 ? 1.0 : 0.0)) * resolution_ - rel[a]) / dir[a];
  };
  // Crossings in distance order; at one distance z's comes first, then y's (RayWalker's order).
  const auto before = [](double t, int a, double u, int b) { return t < u || (t == u && a > b); };
  ConstAccessor cells_of(tree_);
  const NodeWord* words = tree_.words();
  const TreeCoord root = tree_.root().corner;
  for (std::int64_t budget = 3 * cells + 3; budget > 0; --budget) {
    if (k[0] < 0 || k[1] < 0 || k[2] < 0 || k[0] >= cells || k[1] >= cells || k[2] >= cells) break;
    const octree::OctreeKey pk{uindex_t(k[0]), uindex_t(k[1]), uindex_t(k[2])};
    const TreeCoord c(pclKeyToTreeKey(pk));
    // The cube around the cell that the ray crosses at once, 2^span cells per axis in tree coordinates: an
    // empty octant of the tree, or outside the tree's root the largest cube without the root in it.
    unsigned span = 0;
    if (const unsigned level = cells_of.locatePath(c.key()); level == 0)
      span = detail::highestBit((c[0] ^ root[0]) | (c[1] ^ root[1]) | (c[2] ^ root[2]));
    else if (node::state(words[cells_of.pathOffset(level)], c.octant(level)) != CellState::Occupied)
      span = level - 1;
    else if (!visit(pk))
      break;
    std::int64_t face[3];
    double t_face[3];
    for (int a = 0; a < 3; ++a) {
      const std::int64_t lo = k[a] - std::int64_t(c[a] & tree_coord::lowMask(span));
      face[a] = step[a] > 0 ? lo + (std::int64_t(1) << span) - 1 : lo;
      t_face[a] = leave(a, face[a]);
    }
    int exit = 0;
    for (int a = 1; a < 3; ++a)
      if (before(t_face[a], a, t_face[exit], exit)) exit = a;
    // On the other axes, the cell holding the ray as it leaves: past each of their crossings before the exit.
    for (int b = 0; b < 3; ++b) {
      if (b == exit || step[b] == 0 || span == 0) continue;
      const std::int64_t lo = std::min(k[b], face[b]), hi = std::max(k[b], face[b]);
      const double at = std::floor((rel[b] + t_face[exit] * dir[b]) / resolution_);
      std::int64_t j = std::int64_t(std::min<double>(std::max<double>(at, double(lo)), double(hi)));
      while (j != face[b] && before(leave(b, j), b, t_face[exit], exit)) j += step[b];
      while (j != k[b] && !before(leave(b, j - step[b]), b, t_face[exit], exit)) j -= step[b];
      k[b] = j;
    }
    k[exit] = face[exit] + step[exit];
  }
}

OctreeLeafTable::NodeWalk::NodeWalk(const OctreeLeafTable* table, bool depth_first, Stops stops,
                                    uindex_t max_depth)
    : table_(table),
      nodes_(table->nodeArray()),
      depth_first_(depth_first),
      stops_(stops),
      max_depth_(max_depth) {
  pending_.push_back(nodeAt(octree::OctreeKey(0, 0, 0), 0, 0));
  at_end_ = false;
  advance();
}

OctreeLeafTable::Node OctreeLeafTable::NodeWalk::nodeAt(const octree::OctreeKey& key, uindex_t depth,
                                                        std::uint32_t at) const {
  const FlatNode& n = (*nodes_)[at];
  return n.leaf ? Node{key, depth, 0, true, n.first, at} : Node{key, depth, n.children, false, kNoLeaf, at};
}

void OctreeLeafTable::NodeWalk::advance() {
  const uindex_t limit = std::min(max_depth_, table_->depth_);
  while (head_ < pending_.size()) {
    if (depth_first_) {
      node_ = pending_.back();
      pending_.pop_back();
    } else {
      node_ = pending_[head_++];
      if (head_ > 1024 && 2 * head_ > pending_.size()) {  // drop the visited half: memory follows the queue
        pending_.erase(pending_.begin(), pending_.begin() + std::ptrdiff_t(head_));
        head_ = 0;
      }
    }
    if (!node_.leaf && node_.depth < limit) {
      // Children in PCL's order: depth first pushes them last to first, so the first comes out first.
      const std::uint32_t first = (*nodes_)[node_.at].first;
      for (unsigned i = 0; i < 8; ++i) {
        const unsigned c = depth_first_ ? 7 - i : i;
        if (!(node_.children >> c & 1u)) continue;
        const std::uint32_t rank = detail::popcount64(node_.children & ((1u << c) - 1u));
        pending_.push_back(nodeAt(childKey(node_.key, c), node_.depth + 1, first + rank));
      }
    }
    if (stops_ == Stops::All || (stops_ == Stops::Leaves && node_.leaf) ||
        (stops_ == Stops::OneDepth && node_.depth == max_depth_))
      return;
  }
  at_end_ = true;
}

}  // namespace fot
}  // namespace pcl
