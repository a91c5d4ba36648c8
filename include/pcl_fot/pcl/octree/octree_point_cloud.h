#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <typeinfo>
#include <vector>

#include <pcl/memory.h>
#include <pcl/octree/octree_key.h>
#include <pcl/pcl_macros.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>
#include <Eigen/Core>

#include <pcl_fot/pcl/octree/octree_containers.h>
#include <pcl_fot/pcl/octree/octree_leaf_nodes.h>
#include <pcl_fot/pcl/octree/octree_leaf_table.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

/**
 * A FastOctTree with the interface of pcl::octree::OctreePointCloud: code written for it compiles after
 * changing the namespace, and gets the same answers.
 *
 * The bounding box follows PCL exactly: undefined until the first point, which it surrounds with ±res/2;
 * growing by doubling towards points outside it; or set with defineBoundingBox() and padded to a cube of
 * 2^depth cells. Keys, voxel centres and bounds are computed with PCL's arithmetic. The occupied cells
 * live in a FastOctTree at fixed keys, shifted as the box grows.
 *
 * The box, the tree and the table of leaves are an OctreeLeafTable, compiled once for every point type; this
 * class adds the points and the leaves' LeafContainerT, pcl::octree's own container types (point indices by
 * default), one per slot of the table. With OctreeContainerEmpty there are no containers and the tree alone
 * answers (OctreePointCloudOccupancy). Branches hold nothing: BranchContainerT is accepted for PCL's
 * signature only. Under enableDynamicDepth, leaves stay as shallow as PCL keeps them.
 *
 * Differences from pcl::octree, listed in doc/user_guide.md: there is no serializeTree (see the .fot file
 * format); points that are not finite, or that would grow the box beyond ±2^29 cells, are refused with
 * PCL_ERROR rather than asserting.
 */
template <typename PointT, typename LeafContainerT = OctreeContainerPointIndices,
          typename BranchContainerT = OctreeContainerEmpty>
class OctreePointCloud {
 public:
  using Ptr = shared_ptr<OctreePointCloud<PointT, LeafContainerT, BranchContainerT>>;
  using ConstPtr = shared_ptr<const OctreePointCloud<PointT, LeafContainerT, BranchContainerT>>;
  using PointCloud = pcl::PointCloud<PointT>;
  using PointCloudPtr = typename PointCloud::Ptr;
  using PointCloudConstPtr = typename PointCloud::ConstPtr;
  using IndicesPtr = shared_ptr<Indices>;
  using IndicesConstPtr = shared_ptr<const Indices>;
  using AlignedPointTVector = std::vector<PointT, Eigen::aligned_allocator<PointT>>;
  using AlignedPointXYZVector = std::vector<PointXYZ, Eigen::aligned_allocator<PointXYZ>>;
  using SingleBuffer = OctreePointCloud<PointT, LeafContainerT, BranchContainerT>;
  using LeafContainer = LeafContainerT;
  using BranchContainer = BranchContainerT;
  using LeafNode = octree::OctreeLeafNode<LeafContainerT>;
  using BranchNode = octree::OctreeBranchNode<BranchContainerT>;

 private:
  /** Whether leaves hold containers; the occupancy octree's leaves are the tree's cells. */
  static constexpr bool kHoldsLeaves = !std::is_same<LeafContainerT, OctreeContainerEmpty>::value;
  using LeafId = OctreeLeafTable::LeafId;

 protected:
  /** A leaf's number; reading a leaf by its slot leaves its points where they are (no container made). */
  using Slot = OctreeLeafTable::Slot;
  static constexpr Slot kNoLeaf = OctreeLeafTable::kNoLeaf;

 public:
  /**
   * Walks pcl::octree's nodes, branches (the root included) and leaves, in the order of the PCL iterator
   * it stands for: depth first (children in PCL's order) or breadth first, every node or only leaves or
   * one depth, down to a maximum depth. It walks the octree's branches as they were when it was made;
   * adding or deleting points invalidates it, as in PCL.
   */
  class NodeIterator {
   public:
    NodeIterator() = default;
    NodeIterator& operator++() {
      walk_.advance();
      return *this;
    }
    NodeIterator operator++(int) {
      NodeIterator before = *this;
      walk_.advance();
      return before;
    }
    /**
     * As PCL's: iterators of one octree are equal when both are at their end, or when they share their
     * maximum depth and stand on nodes of the same key. Iterators of two octrees are never equal.
     */
    bool operator==(const NodeIterator& o) const { return tree_ == o.tree_ && walk_ == o.walk_; }
    bool operator!=(const NodeIterator& o) const { return !(*this == o); }
    /** As in PCL, a branch's key holds only the bits of its depth. */
    const octree::OctreeKey& getCurrentOctreeKey() const { return walk_.node().key; }
    uindex_t getCurrentOctreeDepth() const { return walk_.node().depth; }
    bool isLeafNode() const { return walk_.node().leaf; }
    bool isBranchNode() const { return !walk_.node().leaf; }
    /** PCL's bit pattern of a branch's children (bit i: child i exists); 0 for a leaf. */
    char getNodeConfiguration() const { return static_cast<char>(walk_.node().children); }
    /**
     * The leaf's node from the octree's table; for a branch, one node of type BRANCH_NODE that all
     * branches share (branches hold nothing here).
     */
    OctreeNode* getCurrentOctreeNode() const {
      if (walk_.node().leaf) return tree_->node(walk_.node().slot);
      return &sharedBranch();
    }
    /** The node it stands on, as getCurrentOctreeNode(); nullptr at the end (PCL's operator*). */
    OctreeNode* operator*() const { return walk_.atEnd() ? nullptr : getCurrentOctreeNode(); }
    /** The leaf's container; only on a leaf. */
    LeafContainerT& getLeafContainer() const { return tree_->node(walk_.node().slot)->getContainer(); }
    /** A branch's container; only on a branch. Branches hold nothing here: they share one empty container. */
    BranchContainerT& getBranchContainer() const { return sharedBranch().getContainer(); }
    /** PCL's node identifier: the node's key, x above y above z, each field the octree's depth wide. */
    unsigned long getNodeID() const {
      const octree::OctreeKey& k = walk_.node().key;
      const uindex_t depth = tree_->getTreeDepth();
      return static_cast<unsigned long>(k.x) << (2 * depth) | static_cast<unsigned long>(k.y) << depth |
             static_cast<unsigned long>(k.z);
    }
    /** Back to the first node, over the octree as it is now (PCL's reset). */
    void reset() { walk_.reset(); }

   private:
    friend class OctreePointCloud;
    using Stops = OctreeLeafTable::Stops;
    NodeIterator(const OctreePointCloud* tree, bool depth_first, Stops stops, uindex_t max_depth)
        : tree_(tree), walk_(&tree->table_, depth_first, stops, max_depth) {}
    /** The one node of type BRANCH_NODE that every branch gives: branches hold nothing here. */
    static BranchNode& sharedBranch() {
      static BranchNode branch;
      return branch;
    }

    const OctreePointCloud* tree_ = nullptr;
    OctreeLeafTable::NodeWalk walk_;
  };
  using Iterator = NodeIterator;
  using ConstIterator = NodeIterator;
  using DepthFirstIterator = NodeIterator;
  using ConstDepthFirstIterator = NodeIterator;
  using BreadthFirstIterator = NodeIterator;
  using ConstBreadthFirstIterator = NodeIterator;
  using FixedDepthIterator = NodeIterator;
  using ConstFixedDepthIterator = NodeIterator;
  using LeafNodeIterator = NodeIterator;
  using ConstLeafNodeIterator = NodeIterator;
  using LeafNodeDepthFirstIterator = NodeIterator;
  using ConstLeafNodeDepthFirstIterator = NodeIterator;
  using LeafNodeBreadthFirstIterator = NodeIterator;
  using ConstLeafNodeBreadthFirstIterator = NodeIterator;

  /** Throws std::invalid_argument for a resolution CellGrid refuses (PCL asserts). */
  OctreePointCloud(const double resolution_arg);
  virtual ~OctreePointCloud() = default;

  void setInputCloud(const PointCloudConstPtr& cloud_arg,
                     const IndicesConstPtr& indices_arg = IndicesConstPtr());
  PointCloudConstPtr getInputCloud() const { return input_; }
  IndicesConstPtr const getIndices() const { return indices_; }
  void setEpsilon(double eps) { epsilon_ = eps; }
  double getEpsilon() const { return epsilon_; }
  /** Only while the tree is empty, as in PCL. */
  void setResolution(double resolution_arg);
  double getResolution() const { return table_.resolution(); }
  uindex_t getTreeDepth() const { return table_.depth(); }
  /** Only before the bounding box is defined, which sets the depth again (as in PCL); 1 to 29. */
  void setTreeDepth(uindex_t depth_arg) { table_.setTreeDepth(depth_arg); }
  /** PCL's: the depth whose keys reach this index, ceil(log2(max_voxel_index_arg)), as setTreeDepth. */
  void setMaxVoxelIndex(uindex_t max_voxel_index_arg) {
    table_.setTreeDepth(max_voxel_index_arg > 1 ? uindex_t(std::ceil(std::log2(max_voxel_index_arg))) : 0u);
  }

  /** Adds every finite point of the input cloud (or of its indices) to its leaf, in index order. */
  void addPointsFromInputCloud();
  /** Adds the input cloud's point point_idx_arg and appends the index to indices_arg, if given. */
  void addPointFromCloud(uindex_t point_idx_arg, IndicesPtr indices_arg);
  /** Appends the point to the input cloud (which must be cloud_arg) and adds it. */
  void addPointToCloud(const PointT& point_arg, PointCloudPtr cloud_arg);
  void addPointToCloud(const PointT& point_arg, PointCloudPtr cloud_arg, IndicesPtr indices_arg);
  /** Creates the point's leaf, holding no point (OctreePointCloudOccupancy's call). */
  void setOccupiedVoxelAtPoint(const PointT& point_arg);
  /** Skips points that are not finite, as PCL does. */
  void setOccupiedVoxelsAtPointsFromCloud(PointCloudPtr cloud_arg);

  /** False outside the bounding box. */
  bool isVoxelOccupiedAtPoint(const PointT& point_arg) const;
  bool isVoxelOccupiedAtPoint(const double point_x_arg, const double point_y_arg,
                              const double point_z_arg) const;
  bool isVoxelOccupiedAtPoint(const index_t& point_idx_arg) const;
  /** The container of the leaf holding the point's voxel; nullptr if there is none. */
  LeafContainerT* findLeafAtPoint(const PointT& point_arg) const;
  /** Deletes the leaf holding the point's voxel (under dynamic depth, the shallow leaf); no-op outside the
   * box. */
  void deleteVoxelAtPoint(const PointT& point_arg);
  void deleteVoxelAtPoint(const index_t& point_idx_arg);

  /** Clears the list, then fills it in pcl::octree's order. */
  uindex_t getOccupiedVoxelCenters(AlignedPointTVector& voxel_center_list_arg) const;
  /**
   * Centres of the occupied voxels a ray from `origin` along `direction` crosses inside the bounding box,
   * near to far, as OctreePointCloudSearch::getIntersectedVoxelCenters; at most max_voxel_count if not 0.
   */
  uindex_t getIntersectedVoxelCenters(Eigen::Vector3f origin, Eigen::Vector3f direction,
                                      AlignedPointTVector& voxel_center_list,
                                      uindex_t max_voxel_count = 0) const;
  /** The point indices of the voxels getIntersectedVoxelCenters finds, voxel by voxel. */
  uindex_t getIntersectedVoxelIndices(Eigen::Vector3f origin, Eigen::Vector3f direction, Indices& k_indices,
                                      uindex_t max_voxel_count = 0) const;
  /** PCL's approximation: samples the segment every res*precision, appends each new voxel's centre. */
  uindex_t getApproxIntersectedVoxelCentersBySegment(const Eigen::Vector3f& origin,
                                                     const Eigen::Vector3f& end,
                                                     AlignedPointTVector& voxel_center_list,
                                                     float precision = 0.2);

  void defineBoundingBox();
  void defineBoundingBox(const double min_x_arg, const double min_y_arg, const double min_z_arg,
                         const double max_x_arg, const double max_y_arg, const double max_z_arg);
  void defineBoundingBox(const double max_x_arg, const double max_y_arg, const double max_z_arg);
  void defineBoundingBox(const double cubeLen_arg);
  void getBoundingBox(double& min_x_arg, double& min_y_arg, double& min_z_arg, double& max_x_arg,
                      double& max_y_arg, double& max_z_arg) const;

  double getVoxelSquaredDiameter(uindex_t tree_depth_arg) const {
    return 3.0 * getVoxelSquaredSideLen(tree_depth_arg);
  }
  double getVoxelSquaredDiameter() const { return getVoxelSquaredDiameter(getTreeDepth()); }
  double getVoxelSquaredSideLen(uindex_t tree_depth_arg) const {
    return table_.voxelSquaredSideLen(tree_depth_arg);
  }
  double getVoxelSquaredSideLen() const { return getVoxelSquaredSideLen(getTreeDepth()); }
  /** The bounds of the node's cube, at its depth, as PCL computes them. */
  void getVoxelBounds(const NodeIterator& iterator, Eigen::Vector3f& min_pt, Eigen::Vector3f& max_pt) const {
    table_.voxelBounds(iterator.getCurrentOctreeKey(), iterator.getCurrentOctreeDepth(), min_pt, max_pt);
  }

  /** Depth-first, children in index order; max_depth_arg 0 means the full depth. */
  NodeIterator begin(uindex_t max_depth_arg = 0u) const {
    return NodeIterator(this, true, NodeIterator::Stops::All, max_depth_arg ? max_depth_arg : getTreeDepth());
  }
  NodeIterator end() const {
    NodeIterator at_end;
    at_end.tree_ = this;
    return at_end;
  }
  NodeIterator cbegin(uindex_t max_depth_arg = 0u) const { return begin(max_depth_arg); }
  NodeIterator cend() const { return end(); }
  NodeIterator depth_begin(uindex_t max_depth_arg = 0u) const { return begin(max_depth_arg); }
  NodeIterator depth_end() const { return end(); }
  /** Level by level, from the root down. */
  NodeIterator breadth_begin(uindex_t max_depth_arg = 0u) const {
    return NodeIterator(this, false, NodeIterator::Stops::All,
                        max_depth_arg ? max_depth_arg : getTreeDepth());
  }
  NodeIterator breadth_end() const { return end(); }
  /** The nodes at one depth, in breadth-first order; none, with PCL_WARN, deeper than the tree. */
  NodeIterator fixed_depth_begin(uindex_t fixed_depth_arg = 0u) const;
  NodeIterator fixed_depth_end() const { return end(); }
  /** The leaves, depth first; those deeper than max_depth_arg are left out. */
  NodeIterator leaf_depth_begin(uindex_t max_depth_arg = 0u) const {
    return NodeIterator(this, true, NodeIterator::Stops::Leaves,
                        max_depth_arg ? max_depth_arg : getTreeDepth());
  }
  NodeIterator leaf_depth_end() const { return end(); }
  /** The leaves, level by level (they differ from depth first only under dynamic depth). */
  NodeIterator leaf_breadth_begin(uindex_t max_depth_arg = 0u) const {
    return NodeIterator(this, false, NodeIterator::Stops::Leaves,
                        max_depth_arg ? max_depth_arg : getTreeDepth());
  }
  NodeIterator leaf_breadth_end() const { return end(); }

  /**
   * The container of the leaf at this PCL key, created if there is none (pcl::octree's createLeaf). nullptr,
   * with PCL_ERROR, before the bounding box is defined or for a key beyond it (where PCL drops the high
   * bits).
   */
  LeafContainerT* createLeaf(uindex_t idx_x_arg, uindex_t idx_y_arg, uindex_t idx_z_arg);
  /**
   * The container of the leaf holding the voxel at this PCL key (under dynamic depth, the shallow leaf);
   * nullptr if there is none, or beyond the box.
   */
  LeafContainerT* findLeaf(uindex_t idx_x_arg, uindex_t idx_y_arg, uindex_t idx_z_arg) const;
  /** Whether the voxel at this PCL key is occupied; false beyond the box, where PCL drops the high bits. */
  bool existLeaf(uindex_t idx_x_arg, uindex_t idx_y_arg, uindex_t idx_z_arg) const {
    return table_.existLeaf(idx_x_arg, idx_y_arg, idx_z_arg);
  }
  /** Deletes the voxel at this PCL key, pruning as PCL does; a no-op beyond the box. */
  virtual void removeLeaf(uindex_t idx_x_arg, uindex_t idx_y_arg, uindex_t idx_z_arg) {
    const Slot gone = table_.removeLeaf(idx_x_arg, idx_y_arg, idx_z_arg);
    if constexpr (kHoldsLeaves)
      if (gone != kNoLeaf) nodes_.drop(gone);
  }

  std::size_t getLeafCount() const { return table_.leafCount(); }
  /** The branch nodes pcl::octree would hold for these voxels, its root included. */
  std::size_t getBranchCount() const { return table_.branchCount(); }
  /** Empties the tree and resets the bounding box; the depth stays, as in PCL. */
  void deleteTree() {
    table_.clear();
    nodes_.clear();
  }
  /**
   * PCL's dynamic depth: a new leaf is made as shallow as the path allows, and a leaf that holds
   * maxObjsPerLeaf points or more splits when the next point arrives. 0 turns it off. Only while the tree is
   * empty. Leaves of OctreeContainerEmpty count no points, so they never split (as in PCL).
   */
  void enableDynamicDepth(std::size_t maxObjsPerLeaf) { table_.enableDynamicDepth(maxObjsPerLeaf); }

  /** The FastOctTree holding the voxels (keys shifted from pcl::octree's; see pclKeyToTreeKey). */
  const FastOctTree& getFastOctTree() const { return table_.tree(); }
  Key pclKeyToTreeKey(const octree::OctreeKey& k) const { return table_.pclKeyToTreeKey(k); }

  PCL_MAKE_ALIGNED_OPERATOR_NEW

 protected:
  /** Adds the input cloud's point point_idx_arg to its leaf; derived look-alikes add it their way. */
  virtual void addPointIdx(uindex_t point_idx_arg);
  /**
   * Whether addPointsFromInputCloud may sort the points into their leaves at once instead of calling
   * addPointIdx for each: only for a class known to add points as this one does. A class derived from it,
   * a user's included, gets addPointIdx called for every point unless it says otherwise.
   */
  virtual bool addsPointsInBulk() const { return typeid(*this) == typeid(OctreePointCloud); }
  /** What adding a point of the input does to its leaf's container: pcl::octree's addPointIndex. */
  virtual void addToLeaf(LeafContainerT& leaf, index_t point) { leaf.addPointIndex(point); }
  /** The leaf holding the voxel at this PCL key, creating it (as PCL's createLeaf) if there is none. */
  LeafNode* createLeaf(const octree::OctreeKey& key);
  /** The leaf holding the voxel at this PCL key; nullptr if none. */
  LeafNode* findLeaf(const octree::OctreeKey& key) const { return node(table_.findLeaf(key)); }
  /** The leaf at this depth and key (a node's key, as iterators give it); nullptr if none. */
  LeafNode* leafAt(const octree::OctreeKey& key, uindex_t depth) const {
    return node(table_.leafAt(key, depth));
  }
  /** The slot of the leaf holding the voxel at this PCL key; kNoLeaf if none. */
  Slot findSlot(const octree::OctreeKey& key) const { return table_.findLeaf(key); }
  /** The slot of the leaf whose voxel holds the point; kNoLeaf if none or outside the box. */
  Slot slotAtPoint(const PointT& point) const {
    if (!isPointWithinBoundingBox(point.x, point.y, point.z)) return kNoLeaf;
    return findSlot(pclKey(point.x, point.y, point.z));
  }
  /** findSlot for many keys at once, into `slots`. */
  void findSlots(const std::vector<octree::OctreeKey>& keys, std::vector<Slot>& slots) const {
    table_.findLeaves(keys, slots);
  }
  /** The slot of the leaf at the iterator. */
  Slot slotAt(const NodeIterator& it) const { return it.walk_.node().slot; }
  /** Appends the point indices of the leaf in this slot. */
  void appendLeafIndices(Slot slot, Indices& out) const {
    if constexpr (kHoldsLeaves) nodes_.appendIndices(slot, out);
  }
  /** The number of points of the leaf in this slot, as its container counts them. */
  std::size_t leafSize(Slot slot) const {
    if constexpr (kHoldsLeaves) return nodes_.size(slot);
    return 0;
  }
  bool isPointWithinBoundingBox(double x, double y, double z) const {
    return table_.isPointWithinBoundingBox(x, y, z);
  }
  /** PCL's key: (point - min) / resolution, truncated; only for points inside the box. */
  octree::OctreeKey pclKey(double x, double y, double z) const { return table_.pclKey(x, y, z); }
  void pclKeyToCenter(const octree::OctreeKey& key, PointT& point) const {
    voxelCenter(key, getTreeDepth(), point);
  }
  /** PCL's genVoxelCenterFromOctreeKey: the centre of the node at this depth and key. */
  void voxelCenter(const octree::OctreeKey& key, uindex_t depth, PointT& point) const {
    double center[3];
    table_.voxelCenter(key, depth, center);
    point.x = static_cast<float>(center[0]);
    point.y = static_cast<float>(center[1]);
    point.z = static_cast<float>(center[2]);
  }
  /** PCL's adoptBoundingBoxToPoint; false (with PCL_ERROR) if the box would leave the key range. */
  bool adoptBoundingBoxToPoint(double x, double y, double z) {
    return table_.adoptBoundingBoxToPoint(x, y, z);
  }
  /** Bumped by every change of the leaves, so that caches built from them know when they are stale. */
  std::uint64_t version() const { return table_.version(); }
  /** Appends the point indices of every leaf, leaf after leaf in no particular order. */
  void appendEveryLeafIndices(Indices& out) const {
    table_.forEachLeaf([&](Slot slot) { appendLeafIndices(slot, out); });
  }
  /** Empties the leaves but keeps the bounding box (a new buffer of OctreePointCloudChangeDetector). */
  void clearLeaves() {
    table_.clearLeaves();
    nodes_.clear();
  }
  /**
   * The leaf pcl::octree's approxNearestSearch descends to: at each depth, the existing child whose centre
   * lies nearest to the point. kNoLeaf if the descent meets an empty old root (where PCL asserts).
   */
  Slot approxSlot(const PointT& point) const { return table_.approxLeaf(point.getVector3fMap()); }

  PointCloudConstPtr input_;
  IndicesConstPtr indices_;

 private:
  /** The leaf node in this slot; nullptr for none. The occupancy octree's leaves share one empty node. */
  LeafNode* node(Slot slot) const {
    if (slot == kNoLeaf) return nullptr;
    if constexpr (kHoldsLeaves) {
      return &nodes_.node(slot);
    } else {
      static LeafNode empty_leaf;
      return &empty_leaf;
    }
  }
  /** The node of a slot the table gives: a new slot's container starts empty. */
  LeafNode* slotNode(Slot slot, bool created);
  /** PCL's expandLeafNode: the leaf becomes a branch, its points go to new leaves one level down. */
  void expandLeaf(const LeafId& id, Slot slot);
  /**
   * Adds points[next..] (finite, of the input) to their leaves by sorting their keys, with the box grown
   * for each in turn as addPointIdx would; the octree already has a leaf. Leaves `next` at the end.
   */
  void addInBulk(Indices& points, std::size_t& next);

  double epsilon_ = 0.0;
  OctreeLeafTable table_;
  OctreeLeafNodes<LeafContainerT> nodes_;  // the leaves' nodes by slot
};

/** PCL's occupancy octree: its leaves are the tree's cells and hold nothing. */
template <typename PointT, typename LeafContainerT = OctreeContainerEmpty,
          typename BranchContainerT = OctreeContainerEmpty>
using OctreePointCloudOccupancy = OctreePointCloud<PointT, LeafContainerT, BranchContainerT>;

}  // namespace fot
}  // namespace pcl

#ifdef PCL_NO_PRECOMPILE
#include <pcl_fot/pcl/octree/impl/octree_point_cloud.hpp>
#endif
