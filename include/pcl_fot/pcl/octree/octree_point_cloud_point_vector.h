#pragma once

#include <pcl_fot/pcl/octree/octree_point_cloud.h>

namespace pcl {
namespace fot {

/** pcl::octree::OctreePointCloudPointVector: each leaf keeps the indices of all its points, in order. */
template <typename PointT, typename LeafContainerT = OctreeContainerPointIndices,
          typename BranchContainerT = OctreeContainerEmpty>
class OctreePointCloudPointVector : public OctreePointCloud<PointT, LeafContainerT, BranchContainerT> {
 public:
  using Ptr = shared_ptr<OctreePointCloudPointVector<PointT, LeafContainerT, BranchContainerT>>;
  using ConstPtr = shared_ptr<const OctreePointCloudPointVector<PointT, LeafContainerT, BranchContainerT>>;

  OctreePointCloudPointVector(const double resolution_arg)
      : OctreePointCloud<PointT, LeafContainerT, BranchContainerT>(resolution_arg) {}

 protected:
  bool addsPointsInBulk() const override { return typeid(*this) == typeid(OctreePointCloudPointVector); }
};

}  // namespace fot
}  // namespace pcl
