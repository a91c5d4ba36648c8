// OctreePointCloudSinglePoint for each point type: a file of its own, so that two jobs compile the family.
#include <pcl_fot/pcl/octree/octree_point_cloud_single_point.h>
#include <pcl_fot/pcl/octree/impl/octree_point_cloud.hpp>

#ifndef PCL_NO_PRECOMPILE
#include "pcl/instantiated_point_types.h"
PCL_INSTANTIATE(OctreePointCloudSinglePoint, PCL_FOT_INSTANTIATED_POINT_TYPES)
#endif
