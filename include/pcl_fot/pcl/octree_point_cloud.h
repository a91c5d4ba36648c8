#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <pcl/memory.h>
#include <pcl/octree/octree_key.h>
#include <pcl/pcl_macros.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>
#include <Eigen/Core>

#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

/**
 * A FastOctTree with the interface of pcl::octree::OctreePointCloud and OctreePointCloudOccupancy: code
 * written for them compiles after changing the type name, and gets the same answers.
 *
 * The bounding box follows PCL exactly: undefined until the first point, which it surrounds with ±res/2;
 * growing by doubling towards points outside it; or set with defineBoundingBox() and padded to a cube of
 * 2^depth cells. Keys, voxel centres and bounds are computed with PCL's arithmetic. The cells themselves
 * live in a FastOctTree at fixed keys, shifted as the box grows.
 *
 * Differences from pcl::octree, listed in doc/user_guide.md: leaves hold occupancy, not point indices (as
 * OctreePointCloudOccupancy); there is no serializeTree (see the .fot file format), no dynamic depth, and
 * iterators yield keys and depths, not node pointers; points that are not finite, or that would grow the box
 * beyond ±2^29 cells, are refused with PCL_ERROR rather than asserting.
 */
template <typename PointT>
class OctreePointCloud {
 public:
  using Ptr = shared_ptr<OctreePointCloud<PointT>>;
  using ConstPtr = shared_ptr<const OctreePointCloud<PointT>>;
  using PointCloud = pcl::PointCloud<PointT>;
  using PointCloudPtr = typename PointCloud::Ptr;
  using PointCloudConstPtr = typename PointCloud::ConstPtr;
  using IndicesPtr = shared_ptr<Indices>;
  using IndicesConstPtr = shared_ptr<const Indices>;
  using AlignedPointTVector = std::vector<PointT, Eigen::aligned_allocator<PointT>>;
  using AlignedPointXYZVector = std::vector<PointXYZ, Eigen::aligned_allocator<PointXYZ>>;
  using SingleBuffer = OctreePointCloud<PointT>;

 private:
  /** One node of the octree pcl::octree would build. */
  struct Node {
    octree::OctreeKey key;
    uindex_t depth;
    std::uint8_t children;  // PCL's child bit pattern
    bool leaf;
  };

 public:
  /**
   * Visits pcl::octree's nodes, branches (the root included) and leaves, in the order of the PCL iterator
   * it stands for. The nodes are listed when the iterator is made: later changes to the octree are not seen.
   */
  class NodeIterator {
   public:
    NodeIterator() = default;
    NodeIterator& operator++() {
      ++at_;
      return *this;
    }
    NodeIterator operator++(int) {
      NodeIterator before = *this;
      ++at_;
      return before;
    }
    /**
     * As PCL's: iterators of one octree are equal when both are at their end, or when they share their
     * maximum depth and stand on nodes of the same key. Iterators of two octrees are never equal.
     */
    bool operator==(const NodeIterator& o) const {
      if (tree_ != o.tree_) return false;
      if (atEnd() || o.atEnd()) return atEnd() && o.atEnd();
      return max_depth_ == o.max_depth_ && node().key == o.node().key;
    }
    bool operator!=(const NodeIterator& o) const { return !(*this == o); }
    /** As in PCL, a branch's key holds only the bits of its depth. */
    const octree::OctreeKey& getCurrentOctreeKey() const { return node().key; }
    uindex_t getCurrentOctreeDepth() const { return node().depth; }
    bool isLeafNode() const { return node().leaf; }
    bool isBranchNode() const { return !node().leaf; }
    /** PCL's bit pattern of a branch's children (bit i: child i exists); 0 for a leaf. */
    char getNodeConfiguration() const { return static_cast<char>(node().children); }

   private:
    friend class OctreePointCloud;
    NodeIterator(const OctreePointCloud* tree, uindex_t max_depth,
                 std::shared_ptr<const std::vector<Node>> nodes)
        : tree_(tree), max_depth_(max_depth), nodes_(std::move(nodes)) {}
    bool atEnd() const { return !nodes_ || at_ >= nodes_->size(); }
    const Node& node() const { return (*nodes_)[at_]; }
    const OctreePointCloud* tree_ = nullptr;
    uindex_t max_depth_ = 0;
    std::shared_ptr<const std::vector<Node>> nodes_;
    std::size_t at_ = 0;
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

  void setInputCloud(const PointCloudConstPtr& cloud_arg,
                     const IndicesConstPtr& indices_arg = IndicesConstPtr());
  PointCloudConstPtr getInputCloud() const { return input_; }
  IndicesConstPtr const getIndices() const { return indices_; }
  void setEpsilon(double eps) { epsilon_ = eps; }
  double getEpsilon() const { return epsilon_; }
  /** Only while the tree is empty, as in PCL. */
  void setResolution(double resolution_arg);
  double getResolution() const { return resolution_; }
  uindex_t getTreeDepth() const { return depth_; }

  /** Adds every finite point of the input cloud (or of its indices). */
  void addPointsFromInputCloud();
  /** Appends the point to the input cloud (which must be cloud_arg) and adds it. */
  /** Adds the input cloud's point point_idx_arg and appends the index to indices_arg, if given. */
  void addPointFromCloud(uindex_t point_idx_arg, IndicesPtr indices_arg);
  void addPointToCloud(const PointT& point_arg, PointCloudPtr cloud_arg);
  void addPointToCloud(const PointT& point_arg, PointCloudPtr cloud_arg, IndicesPtr indices_arg);
  void setOccupiedVoxelAtPoint(const PointT& point_arg);
  /** Skips points that are not finite, as PCL does. */
  void setOccupiedVoxelsAtPointsFromCloud(PointCloudPtr cloud_arg);

  /** False outside the bounding box. */
  bool isVoxelOccupiedAtPoint(const PointT& point_arg) const;
  bool isVoxelOccupiedAtPoint(const double point_x_arg, const double point_y_arg,
                              const double point_z_arg) const;
  bool isVoxelOccupiedAtPoint(const index_t& point_idx_arg) const;
  /** No-op outside the bounding box. */
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
  double getVoxelSquaredDiameter() const { return getVoxelSquaredDiameter(depth_); }
  double getVoxelSquaredSideLen(uindex_t tree_depth_arg) const;
  double getVoxelSquaredSideLen() const { return getVoxelSquaredSideLen(depth_); }
  /** The bounds of the node's cube, at its depth, as PCL computes them. */
  void getVoxelBounds(const NodeIterator& iterator, Eigen::Vector3f& min_pt, Eigen::Vector3f& max_pt) const;

  /** Depth-first, children in index order; max_depth_arg 0 means the full depth. */
  NodeIterator begin(uindex_t max_depth_arg = 0u) const;
  NodeIterator end() const { return NodeIterator(this, 0, nullptr); }
  NodeIterator cbegin(uindex_t max_depth_arg = 0u) const { return begin(max_depth_arg); }
  NodeIterator cend() const { return end(); }
  NodeIterator depth_begin(uindex_t max_depth_arg = 0u) const { return begin(max_depth_arg); }
  NodeIterator depth_end() const { return end(); }
  /** Level by level, from the root down. */
  NodeIterator breadth_begin(uindex_t max_depth_arg = 0u) const;
  NodeIterator breadth_end() const { return end(); }
  /** The nodes at one depth, in breadth-first order; none, with PCL_WARN, deeper than the tree. */
  NodeIterator fixed_depth_begin(uindex_t fixed_depth_arg = 0u) const;
  NodeIterator fixed_depth_end() const { return end(); }
  /** The leaves; none when max_depth_arg stops above them. */
  NodeIterator leaf_depth_begin(uindex_t max_depth_arg = 0u) const;
  NodeIterator leaf_depth_end() const { return end(); }
  /** Every leaf lies at the full depth, so breadth-first order is depth-first order, as in pcl::octree. */
  NodeIterator leaf_breadth_begin(uindex_t max_depth_arg = 0u) const {
    return leaf_depth_begin(max_depth_arg);
  }
  NodeIterator leaf_breadth_end() const { return end(); }

  /** Whether the voxel at this PCL key is occupied; false beyond the box, where PCL drops the high bits. */
  bool existLeaf(uindex_t idx_x_arg, uindex_t idx_y_arg, uindex_t idx_z_arg) const;
  /** Deletes the voxel at this PCL key, pruning as PCL does; a no-op beyond the box. */
  void removeLeaf(uindex_t idx_x_arg, uindex_t idx_y_arg, uindex_t idx_z_arg);

  std::size_t getLeafCount() const { return std::size_t(tree_.getOccupiedCount()); }
  /** The branch nodes pcl::octree would hold for these voxels, its root included. */
  std::size_t getBranchCount() const;
  /** Empties the tree and resets the bounding box; the depth stays, as in PCL. */
  void deleteTree();

  /** The FastOctTree holding the voxels (keys shifted from pcl::octree's; see pclKeyToTreeKey). */
  const FastOctTree& getFastOctTree() const { return tree_; }
  Key pclKeyToTreeKey(const octree::OctreeKey& k) const {
    return Key{std::int32_t(k.x) + offset_[0], std::int32_t(k.y) + offset_[1],
               std::int32_t(k.z) + offset_[2]};
  }

  PCL_MAKE_ALIGNED_OPERATOR_NEW

 private:
  bool isPointWithinBoundingBox(double x, double y, double z) const {
    return !(x < min_[0] || y < min_[1] || z < min_[2] || x >= max_[0] || y >= max_[1] || z >= max_[2]);
  }
  /** PCL's key: (point - min) / resolution, truncated; only for points inside the box. */
  octree::OctreeKey pclKey(double x, double y, double z) const;
  void pclKeyToCenter(const octree::OctreeKey& key, PointT& point) const;
  /** PCL's adoptBoundingBoxToPoint; false (with PCL_ERROR) if the box would leave the key range. */
  bool adoptBoundingBoxToPoint(double x, double y, double z);
  void getKeyBitSize();
  /** The occupied voxels' PCL keys in pcl::octree's depth-first order. */
  std::vector<octree::OctreeKey> sortedLeafKeys() const;
  /** The nodes pcl::octree would hold for these voxels, in its depth-first order, down to max_depth (0: all).
   */
  std::vector<Node> depthFirstNodes(uindex_t max_depth) const;
  /** An iterator's maximum depth, as PCL's keeps it: the tree's depth for 0. */
  uindex_t iteratorDepth(uindex_t max_depth) const { return max_depth == 0 ? depth_ : max_depth; }

  PointCloudConstPtr input_;
  IndicesConstPtr indices_;
  double epsilon_ = 0.0;
  double resolution_;
  double min_[3] = {0, 0, 0}, max_[3] = {0, 0, 0};
  bool bounding_box_defined_ = false;
  uindex_t depth_ = 0;
  std::array<std::int32_t, 3> offset_{};  // tree key = PCL key + offset
  FastOctTree tree_;
  /**
   * Growing the box of an octree without voxels leaves PCL's old root behind as an empty branch, which
   * only a deletion beneath it removes. These nested cubes (tree keys) keep getBranchCount exact.
   */
  struct Phantom {
    Key min;
    uindex_t level;
  };
  std::vector<Phantom> phantoms_;
};

/** The name under which PCL offers occupancy octrees. */
template <typename PointT>
using OctreePointCloudOccupancy = OctreePointCloud<PointT>;

}  // namespace fot
}  // namespace pcl

#ifdef PCL_NO_PRECOMPILE
#include <pcl_fot/pcl/impl/octree_point_cloud.hpp>
#endif
