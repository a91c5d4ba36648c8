#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include <pcl/octree/octree_key.h>
#include <pcl/pcl_macros.h>
#include <pcl/types.h>
#include <Eigen/Core>

#include <pcl_fot/detail/version_cache.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

/**
 * What the pcl::octree look-alikes share whatever their point type: PCL's bounding box and keys, the
 * FastOctTree of occupied cells, and the table of leaves, which it keeps in step with the tree. A leaf is a
 * slot number; the look-alike keeps its containers in a sequence indexed by slot (a removed leaf's slot is
 * given to a later one). Without containers (the occupancy octree) the tree's cells are the leaves, all in
 * slot 0. Every change of the leaves bumps version(), so caches built from them know when they are stale.
 *
 * Compiled once in the library: the look-alikes' templates hold only what touches points and containers.
 */
class PCL_EXPORTS OctreeLeafTable {
 public:
  using Slot = std::uint32_t;
  static constexpr Slot kNoLeaf = ~Slot(0);

  /** A leaf's cube: its lowest cell's tree key and its level (2^level cells per axis). */
  struct LeafId {
    Key corner;
    std::uint32_t level;
    bool operator==(const LeafId& o) const {
      return corner.x == o.corner.x && corner.y == o.corner.y && corner.z == o.corner.z && level == o.level;
    }
  };
  struct LeafIdHash {
    std::size_t operator()(const LeafId& id) const;
  };
  /**
   * Cubes to values, open addressing with linear probing: a look-up reads a cache line or two and an entry
   * costs no allocation (a node-based map's look-ups and allocations were a third of a build).
   */
  template <typename Value>
  class CubeMap {
   public:
    /** The value of the cube; nullptr if it has none. */
    const Value* find(const LeafId& id) const;
    Value* find(const LeafId& id) { return const_cast<Value*>(std::as_const(*this).find(id)); }
    /**
     * The value of the cube, added value-initialised if it has none (`added` says which): one probe where
     * find and insert take two. Valid until the next change of the map.
     */
    Value& findOrAdd(const LeafId& id, bool& added);
    /** Brings the cube's home entry towards the cache, for a look-up soon. */
    void prefetch(const LeafId& id) const {
      if (!entries_.empty()) __builtin_prefetch(&entries_[home(id)]);
    }
    /** Removes the cube; false if it has no value. */
    bool erase(const LeafId& id);
    std::size_t size() const { return size_; }
    void clear();
    /** Room for n cubes without growing. */
    void reserve(std::size_t n);
    template <typename Visit>
    void forEach(Visit&& visit) const {
      for (const Entry& e : entries_)
        if (e.used) visit(e.id, e.value);
    }

   private:
    struct Entry {
      LeafId id{};
      Value value{};
      bool used = false;
    };
    std::size_t home(const LeafId& id) const { return LeafIdHash()(id) & (entries_.size() - 1); }
    void grow(std::size_t capacity);

    std::vector<Entry> entries_;  // a power of two, at most half full
    std::size_t size_ = 0;
  };
  /** PCL's branches: each one's cube, with the bit pattern of its children (bit i: child i exists). */
  using BranchIndex = CubeMap<std::uint8_t>;

  /** One node of the octree pcl::octree would build. */
  struct Node {
    octree::OctreeKey key;  // as in PCL, only the bits of its depth
    uindex_t depth;
    std::uint8_t children;  // PCL's child bit pattern; 0 for a leaf
    bool leaf;
    Slot slot;         // a leaf's slot (0 for the occupancy octree's cells); kNoLeaf for a branch
    std::uint32_t at;  // its place in the walk's node array
  };

  /** Which nodes a walk stops at. */
  enum class Stops : std::uint8_t { All, Leaves, OneDepth };

  /**
   * pcl::octree's nodes as one array, for walks without look-ups: a branch's children sit together in PCL's
   * order from `first`; a leaf keeps its slot there.
   */
  struct FlatNode {
    std::uint32_t first;    // a branch's first child; a leaf's slot
    std::uint8_t children;  // PCL's child bit pattern; 0 for a leaf or an empty branch
    bool leaf;
  };
  using NodeArray = std::vector<FlatNode>;

  /**
   * Walks pcl::octree's nodes in the order of the PCL iterator it stands for: depth first (children in
   * PCL's order) or breadth first, every node or only leaves or one depth, down to a maximum depth. It walks
   * the branches as they were when it was made.
   */
  class PCL_EXPORTS NodeWalk {
   public:
    NodeWalk() = default;
    NodeWalk(const OctreeLeafTable* table, bool depth_first, Stops stops, uindex_t max_depth);
    /** On to the next node the walk stops at, or to the end. */
    void advance();
    /** Back to the first node, over the branches as they are now; a walk made at its end stays there. */
    void reset() {
      if (table_) *this = NodeWalk(table_, depth_first_, stops_, max_depth_);
    }
    bool atEnd() const { return at_end_; }
    const Node& node() const { return node_; }
    /** As PCL's iterators: equal when both are at their end, or on nodes of one key at one maximum depth. */
    bool operator==(const NodeWalk& o) const {
      if (at_end_ || o.at_end_) return at_end_ && o.at_end_;
      return max_depth_ == o.max_depth_ && node_.key == o.node_.key;
    }

   private:
    /** The node at this key and depth, at this place of the node array. */
    Node nodeAt(const octree::OctreeKey& key, uindex_t depth, std::uint32_t at) const;

    const OctreeLeafTable* table_ = nullptr;
    std::shared_ptr<const NodeArray> nodes_;
    bool depth_first_ = true;
    Stops stops_ = Stops::All;
    uindex_t max_depth_ = 0;
    Node node_{};
    bool at_end_ = true;
    // The nodes still to visit: depth first takes the last (children pushed last to first), breadth first
    // the one at head_. A vector, not a deque: an iterator at the end, made at every loop test against
    // end(), allocates nothing.
    std::vector<Node> pending_;
    std::size_t head_ = 0;
  };

  /** Throws std::invalid_argument for a resolution CellGrid refuses (PCL asserts). */
  OctreeLeafTable(double resolution, bool holds_leaves);

  /** PCL's child `child` (0..7, bit 2 x, bit 1 y, bit 0 z) of the node at key, one depth down. */
  static octree::OctreeKey childKey(const octree::OctreeKey& key, unsigned child) {
    return octree::OctreeKey(key.x << 1 | (child >> 2 & 1u), key.y << 1 | (child >> 1 & 1u),
                             key.z << 1 | (child & 1u));
  }
  /** The PCL key of the first voxel of the node at key, `level` depths above the voxels. */
  static octree::OctreeKey firstVoxel(const octree::OctreeKey& key, std::uint32_t level) {
    return octree::OctreeKey(key.x << level, key.y << level, key.z << level);
  }

  // The bounding box and PCL's keys.
  /** Only while there are no leaves, as in PCL; false (with PCL_ERROR) otherwise or for a bad resolution. */
  bool setResolution(double resolution);
  double resolution() const { return resolution_; }
  uindex_t depth() const { return depth_; }
  /**
   * PCL's setTreeDepth: only before the bounding box is defined (which then sets the depth again, as in PCL),
   * and 1 to 29; false (with PCL_ERROR) otherwise. PCL changes the depth of a defined box without the box.
   */
  bool setTreeDepth(uindex_t depth);
  bool boxDefined() const { return bounding_box_defined_; }
  void getBoundingBox(double min[3], double max[3]) const;
  /** PCL's defineBoundingBox: only while empty, finite and at most 2^29 cells per axis (else PCL_ERROR). */
  void defineBoundingBox(const double min[3], const double max[3]);
  /** PCL's adoptBoundingBoxToPoint; false (with PCL_ERROR) if the box would leave the key range. */
  bool adoptBoundingBoxToPoint(double x, double y, double z);
  bool isPointWithinBoundingBox(double x, double y, double z) const {
    return !(x < min_[0] || y < min_[1] || z < min_[2] || x >= max_[0] || y >= max_[1] || z >= max_[2]);
  }
  /** PCL's key: (point - min) / resolution, truncated; only for points inside the box. */
  octree::OctreeKey pclKey(double x, double y, double z) const;
  Key pclKeyToTreeKey(const octree::OctreeKey& k) const {
    return Key{std::int32_t(k.x) + offset_[0], std::int32_t(k.y) + offset_[1],
               std::int32_t(k.z) + offset_[2]};
  }
  /** PCL's genVoxelCenterFromOctreeKey: the centre of the node at this depth and key, in double. */
  void voxelCenter(const octree::OctreeKey& key, uindex_t depth, double center[3]) const;
  double voxelSquaredSideLen(uindex_t depth) const;
  /** The bounds of the node's cube, at its depth, as PCL computes them. */
  void voxelBounds(const octree::OctreeKey& key, uindex_t depth, Eigen::Vector3f& min_pt,
                   Eigen::Vector3f& max_pt) const;

  // The leaves.
  bool holdsLeaves() const { return holds_leaves_; }
  std::size_t leafCount() const {
    return holds_leaves_ ? leaves_.size() : std::size_t(tree_.getOccupiedCount());
  }
  /** The branch nodes pcl::octree would hold for these voxels, its root included. */
  std::size_t branchCount() const { return branchIndex()->size(); }
  std::uint64_t version() const { return version_; }
  const FastOctTree& tree() const { return tree_; }
  /** PCL's dynamic depth (0: off); only while there are no leaves (else PCL_ERROR). */
  void enableDynamicDepth(std::size_t max_objs_per_leaf);
  std::size_t maxObjsPerLeaf() const { return max_objs_per_leaf_; }

  /** The leaf holding the voxel at this PCL key (the first leaf on its path); kNoLeaf if none. */
  Slot findLeaf(const octree::OctreeKey& key) const;
  /**
   * findLeaf for many keys at once, into `slots`: without dynamic depth the table's probes run ahead of the
   * look-ups, as each is a cache miss.
   */
  void findLeaves(const std::vector<octree::OctreeKey>& keys, std::vector<Slot>& slots) const;
  /** The leaf at this depth and key (a node's key, as iterators give it); kNoLeaf if none. */
  Slot leafAt(const octree::OctreeKey& key, uindex_t depth) const;
  /**
   * The leaf holding the voxel at this PCL key, created as PCL's createLeaf if there is none (its cell is
   * marked). `created` tells whether the slot is new: its container must start empty.
   */
  Slot createLeaf(const octree::OctreeKey& key, bool& created);
  /**
   * The leaf a point at tree key k goes to, created if there is none; `id` is its cube. Under dynamic depth
   * the point's cell is not marked yet (a leaf about to split must not see it): markCell once the point is
   * in.
   */
  Slot leafForPoint(const Key& k, LeafId& id, bool& created);
  void markCell(const Key& k) { tree_.setCell(k, CellState::Occupied); }
  /**
   * The leaves of many points at once, as leafForPoint finds or makes them point by point, without dynamic
   * depth: the keys are sorted, so that each leaf costs one look-up rather than each point. Calls
   * visit(slot, created, first, last) once per leaf, with the positions [first, last) into `keys` of its
   * points, in the order of `keys`.
   */
  template <typename Visit>
  void leavesOfKeys(const std::vector<Key>& keys, Visit&& visit) {
    const std::vector<std::uint32_t> order = cellOrder(keys);
    std::vector<Key> cells;
    std::vector<std::uint32_t> starts;  // each cell's first position in `order`, and the end
    for (std::size_t i = 0; i < order.size(); ++i) {
      const Key& k = keys[order[i]];
      if (i == 0 || !(k.x == cells.back().x && k.y == cells.back().y && k.z == cells.back().z)) {
        cells.push_back(k);
        starts.push_back(std::uint32_t(i));
      }
    }
    starts.push_back(std::uint32_t(order.size()));
    std::vector<Slot> slots;
    std::vector<bool> created;
    leavesOfCells(cells, slots, created);
    for (std::size_t c = 0; c < cells.size(); ++c)
      visit(slots[c], bool(created[c]), order.data() + starts[c], order.data() + starts[c + 1]);
  }
  /** The leaf of this cube, created if there is none (PCL's expandLeafNode fills new leaves this way). */
  Slot leafOfCube(const LeafId& id, bool& created);
  /** Takes a leaf out of the table (PCL's expandLeafNode: its points go to new leaves); its slot is freed. */
  void eraseLeaf(const LeafId& id);
  /** The cube at this level holding the tree key k, aligned on PCL's grid. */
  LeafId cubeOf(const Key& k, std::uint32_t level) const;
  /** Whether the voxel at this PCL key is occupied; false beyond the box, where PCL drops the high bits. */
  bool existLeaf(uindex_t x, uindex_t y, uindex_t z) const;
  /**
   * Deletes the leaf holding the voxel at this PCL key, pruning as PCL does; a no-op beyond the box. Returns
   * the deleted leaf's slot (kNoLeaf if none, or for the occupancy octree).
   */
  Slot removeLeaf(uindex_t x, uindex_t y, uindex_t z);
  /** Empties the leaves but keeps the bounding box. */
  void clearLeaves();
  /** Empties the leaves and resets the bounding box; the depth stays, as in PCL. */
  void clear();
  /** Calls visit(slot) for every leaf, in no particular order. */
  template <typename Visit>
  void forEachLeaf(Visit&& visit) const {
    leaves_.forEach([&](const LeafId&, Slot slot) { visit(slot); });
  }

  // Walks.
  /** The branches of pcl::octree, built from the leaves at the first walk after a change. */
  std::shared_ptr<const BranchIndex> branchIndex() const;
  /**
   * The leaf pcl::octree's approxNearestSearch descends to: at each depth, the existing child whose centre
   * lies nearest to the point (in float, as PCL). kNoLeaf if the descent meets an empty old root.
   */
  Slot approxLeaf(const Eigen::Vector3f& point) const;
  /**
   * Calls visit(key) for each occupied voxel a ray from `origin` along `direction` crosses in the box, near
   * to far, while it returns true.
   */
  void walkRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
               const std::function<bool(const octree::OctreeKey&)>& visit) const;
  /**
   * PCL's getApproxIntersectedVoxelCentersBySegment: samples the segment every resolution * precision and
   * calls visit(key) for each sample in the box whose voxel differs from the last one's. False (with
   * PCL_ERROR) for a segment it refuses.
   */
  bool walkSegment(const Eigen::Vector3f& origin, const Eigen::Vector3f& end, float precision,
                   const std::function<void(const octree::OctreeKey&)>& visit) const;

 private:
  /**
   * The leaves of distinct cells sorted as cellOrder sorts them, found or made as leafForPoint does without
   * dynamic depth, with their slots and whether each is new: the table's probes run ahead of the inserts, the
   * new cells go into the tree in that order through one accessor, and the branch index follows once.
   */
  void leavesOfCells(const std::vector<Key>& cells, std::vector<Slot>& slots, std::vector<bool>& created);
  /** The positions of `keys` sorted by cell (a radix sort), equal keys in their order. */
  static std::vector<std::uint32_t> cellOrder(const std::vector<Key>& keys);
  /** Whether the cube holds an occupied cell or an empty old root. */
  bool cubeHasContent(const LeafId& cube) const;
  /** The first leaf on the path to tree key k, as PCL's descent finds it; `id` is its cube, or where PCL
   * would create it. */
  Slot leafOnPath(const Key& k, LeafId& id) const;
  /** A new leaf of this cube in a free slot. */
  Slot addLeaf(const LeafId& id);
  /** A free slot for a new leaf. */
  Slot takeSlot();
  /** The slot of the leaf of this cube; kNoLeaf if none. */
  Slot leafOf(const LeafId& id) const {
    const Slot* slot = leaves_.find(id);
    return slot ? *slot : kNoLeaf;
  }
  void getKeyBitSize();
  std::shared_ptr<BranchIndex> buildBranchIndex() const;
  /** The walks' node array, built from the leaves at the first walk after a change. */
  std::shared_ptr<const NodeArray> nodeArray() const;
  std::shared_ptr<NodeArray> buildNodeArray() const;
  /** The node's place among its parent's children, in PCL's order. */
  unsigned childIndex(const LeafId& node) const;
  /** Marks the node (a leaf's cube) in its parent, and each new parent in its own, up to the root. */
  void addToBranches(BranchIndex& index, LeafId node) const;
  /** Unmarks the node (a leaf's cube) in its parent, and removes each parent left without children. */
  void removeFromBranches(BranchIndex& index, LeafId node) const;

  double resolution_;
  bool holds_leaves_;
  double min_[3] = {0, 0, 0}, max_[3] = {0, 0, 0};
  uindex_t depth_ = 0;
  bool bounding_box_defined_ = false;
  std::array<std::int32_t, 3> offset_{};  // tree key = PCL key + offset
  FastOctTree tree_;
  CubeMap<Slot> leaves_;  // only when holds_leaves_
  std::vector<Slot> free_slots_;
  Slot next_slot_ = 0;
  /** The leaf the last point went to (a scan's next point often shares it). */
  LeafId last_id_{};
  Slot last_slot_ = kNoLeaf;
  std::size_t max_objs_per_leaf_ = 0;  // 0: no dynamic depth
  std::uint64_t version_ = 0;
  mutable detail::VersionCache<BranchIndex> branch_cache_;  // for the branch count and the approximate search
  mutable detail::VersionCache<NodeArray> node_cache_;      // the node array of the last walk
  /**
   * Growing the box of an octree without voxels leaves PCL's old root behind as an empty branch, which
   * only a deletion beneath it removes. These nested cubes (tree keys) keep branchCount exact.
   */
  struct Phantom {
    Key min;
    uindex_t level;
  };
  std::vector<Phantom> phantoms_;
};

}  // namespace fot
}  // namespace pcl
