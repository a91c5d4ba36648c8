#pragma once

#include <pcl/common/point_tests.h>
#include <pcl/console/print.h>

#include <pcl_fot/pcl/octree/octree_point_cloud.h>

namespace pcl {
namespace fot {

/** pcl::octree::OctreePointCloudVoxelCentroid: each leaf sums its points; centroids in PCL's leaf order. */
template <typename PointT, typename LeafContainerT = OctreePointCloudVoxelCentroidContainer<PointT>,
          typename BranchContainerT = OctreeContainerEmpty>
class OctreePointCloudVoxelCentroid : public OctreePointCloud<PointT, LeafContainerT, BranchContainerT> {
 public:
  using OctreeT = OctreePointCloud<PointT, LeafContainerT, BranchContainerT>;
  using Ptr = shared_ptr<OctreePointCloudVoxelCentroid<PointT, LeafContainerT, BranchContainerT>>;
  using ConstPtr = shared_ptr<const OctreePointCloudVoxelCentroid<PointT, LeafContainerT, BranchContainerT>>;
  using typename OctreeT::AlignedPointTVector;
  using typename OctreeT::LeafNode;

  OctreePointCloudVoxelCentroid(const double resolution_arg) : OctreeT(resolution_arg) {}

  /** The centroid of the voxel of point_arg; false (centroid untouched) where there is no leaf. */
  bool getVoxelCentroidAtPoint(const PointT& point_arg, PointT& voxel_centroid_arg) const {
    const LeafContainerT* leaf = this->findLeafAtPoint(point_arg);
    if (leaf) leaf->getCentroid(voxel_centroid_arg);
    return leaf != nullptr;
  }
  bool getVoxelCentroidAtPoint(const index_t& point_idx_arg, PointT& voxel_centroid_arg) const {
    if (!this->input_ || point_idx_arg < 0 || std::size_t(point_idx_arg) >= this->input_->size()) {
      PCL_ERROR("[pcl::fot::OctreePointCloudVoxelCentroid] Index %d is not in the input cloud.\n",
                point_idx_arg);
      return false;
    }
    return getVoxelCentroidAtPoint((*this->input_)[point_idx_arg], voxel_centroid_arg);
  }
  /** Clears the list, then fills it leaf by leaf in PCL's depth-first order. */
  uindex_t getVoxelCentroids(AlignedPointTVector& voxel_centroid_list_arg) const {
    voxel_centroid_list_arg.clear();
    voxel_centroid_list_arg.reserve(this->getLeafCount());
    for (auto it = this->leaf_depth_begin(); it != this->leaf_depth_end(); ++it) {
      PointT centroid;
      it.getLeafContainer().getCentroid(centroid);
      voxel_centroid_list_arg.push_back(centroid);
    }
    return static_cast<uindex_t>(voxel_centroid_list_arg.size());
  }

 protected:
  /** As PCL: the point itself goes to its leaf, which never splits. */
  void addPointIdx(uindex_t point_idx_arg) override {
    const PointT& point = (*this->input_)[point_idx_arg];
    if (!isFinite(point)) {
      PCL_ERROR("[pcl::fot::OctreePointCloudVoxelCentroid] Point %zu is not finite; it is not added.\n",
                static_cast<std::size_t>(point_idx_arg));
      return;
    }
    if (!this->adoptBoundingBoxToPoint(point.x, point.y, point.z)) return;
    addToLeaf(this->createLeaf(this->pclKey(point.x, point.y, point.z))->getContainer(),
              static_cast<index_t>(point_idx_arg));
  }
  void addToLeaf(LeafContainerT& leaf, index_t point) override { leaf.addPoint((*this->input_)[point]); }
  bool addsPointsInBulk() const override { return typeid(*this) == typeid(OctreePointCloudVoxelCentroid); }
};

}  // namespace fot
}  // namespace pcl
