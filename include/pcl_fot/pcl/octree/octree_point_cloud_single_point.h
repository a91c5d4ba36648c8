#pragma once

#include <pcl_fot/pcl/octree/octree_point_cloud.h>

namespace pcl {
namespace fot {

/** pcl::octree::OctreePointCloudSinglePoint: each leaf keeps the index of the last point added to it. */
template <typename PointT, typename LeafContainerT = OctreeContainerPointIndex,
          typename BranchContainerT = OctreeContainerEmpty>
class OctreePointCloudSinglePoint : public OctreePointCloud<PointT, LeafContainerT, BranchContainerT> {
 public:
  using Ptr = shared_ptr<OctreePointCloudSinglePoint<PointT, LeafContainerT, BranchContainerT>>;
  using ConstPtr = shared_ptr<const OctreePointCloudSinglePoint<PointT, LeafContainerT, BranchContainerT>>;

  OctreePointCloudSinglePoint(const double resolution_arg)
      : OctreePointCloud<PointT, LeafContainerT, BranchContainerT>(resolution_arg) {}

 protected:
  bool addsPointsInBulk() const override { return typeid(*this) == typeid(OctreePointCloudSinglePoint); }
};

}  // namespace fot
}  // namespace pcl
