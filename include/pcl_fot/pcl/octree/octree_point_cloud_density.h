#pragma once

#include <pcl_fot/pcl/octree/octree_point_cloud.h>

namespace pcl {
namespace fot {

/** pcl::octree::OctreePointCloudDensity: each leaf counts its points. */
template <typename PointT, typename LeafContainerT = OctreePointCloudDensityContainer,
          typename BranchContainerT = OctreeContainerEmpty>
class OctreePointCloudDensity : public OctreePointCloud<PointT, LeafContainerT, BranchContainerT> {
 public:
  using Ptr = shared_ptr<OctreePointCloudDensity<PointT, LeafContainerT, BranchContainerT>>;
  using ConstPtr = shared_ptr<const OctreePointCloudDensity<PointT, LeafContainerT, BranchContainerT>>;

  OctreePointCloudDensity(const double resolution_arg)
      : OctreePointCloud<PointT, LeafContainerT, BranchContainerT>(resolution_arg) {}

  /** The points in the voxel of point_arg; 0 where there is no leaf. */
  uindex_t getVoxelDensityAtPoint(const PointT& point_arg) const {
    const LeafContainerT* leaf = this->findLeafAtPoint(point_arg);
    return leaf ? leaf->getPointCounter() : 0;
  }

 protected:
  bool addsPointsInBulk() const override { return typeid(*this) == typeid(OctreePointCloudDensity); }
};

}  // namespace fot
}  // namespace pcl
