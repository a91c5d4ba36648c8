#pragma once

#include <pcl_fot/pcl/octree/octree_point_cloud.h>

namespace pcl {
namespace fot {

/**
 * pcl::octree::OctreePointCloudChangeDetector: two buffers, the previous one kept as a FastOctTree of its
 * occupied cells. switchBuffers() makes the current buffer the previous one and starts an empty one in the
 * same bounding box; getPointIndicesFromNewVoxels() lists the points of the current leaves whose voxels the
 * previous buffer did not hold, leaf by leaf in PCL's depth-first order.
 */
template <typename PointT, typename LeafContainerT = OctreeContainerPointIndices,
          typename BranchContainerT = OctreeContainerEmpty>
class OctreePointCloudChangeDetector : public OctreePointCloud<PointT, LeafContainerT, BranchContainerT> {
 public:
  using OctreeT = OctreePointCloud<PointT, LeafContainerT, BranchContainerT>;
  using Ptr = shared_ptr<OctreePointCloudChangeDetector<PointT, LeafContainerT, BranchContainerT>>;
  using ConstPtr = shared_ptr<const OctreePointCloudChangeDetector<PointT, LeafContainerT, BranchContainerT>>;

  OctreePointCloudChangeDetector(const double resolution_arg)
      : OctreeT(resolution_arg), previous_(resolution_arg) {}

  void switchBuffers() {
    previous_ = this->getFastOctTree();
    this->clearLeaves();
  }
  /** Forgets the previous buffer: every voxel counts as new. */
  void deletePreviousBuffer() { previous_.clear(); }
  /** Empties the current buffer (the previous one stays). */
  void deleteCurrentBuffer() { this->clearLeaves(); }

  /**
   * Appends the indices of the points in new voxels holding at least minPointsPerLeaf_arg points; returns
   * the list's size.
   */
  uindex_t getPointIndicesFromNewVoxels(Indices& indicesVector_arg,
                                        const uindex_t minPointsPerLeaf_arg = 0) const {
    for (auto it = this->leaf_depth_begin(); it != this->leaf_depth_end(); ++it) {
      const octree::OctreeKey& key = it.getCurrentOctreeKey();
      const uindex_t level = this->getTreeDepth() - it.getCurrentOctreeDepth();
      const octree::OctreeKey first_voxel = OctreeLeafTable::firstVoxel(key, level);
      if (previous_.getCell(this->pclKeyToTreeKey(first_voxel)) == CellState::Occupied) continue;
      const auto leaf = this->slotAt(it);
      if (static_cast<uindex_t>(this->leafSize(leaf)) >= minPointsPerLeaf_arg)
        this->appendLeafIndices(leaf, indicesVector_arg);
    }
    return static_cast<uindex_t>(indicesVector_arg.size());
  }

 protected:
  bool addsPointsInBulk() const override { return typeid(*this) == typeid(OctreePointCloudChangeDetector); }

 private:
  FastOctTree previous_;
};

}  // namespace fot
}  // namespace pcl
