// OctreePointCloud with point indices in its leaves, and the occupancy octree, for each point type.
#include <pcl_fot/pcl/octree/octree_point_cloud.h>
#include <pcl_fot/pcl/octree/impl/octree_point_cloud.hpp>

#ifndef PCL_NO_PRECOMPILE
#include "pcl/instantiated_point_types.h"
PCL_INSTANTIATE(OctreePointCloud, PCL_FOT_INSTANTIATED_POINT_TYPES)
PCL_INSTANTIATE(OctreePointCloudOccupancy, PCL_FOT_INSTANTIATED_POINT_TYPES)
#endif
