// OctreePointCloudAdjacency for each point type.
#include <pcl_fot/pcl/octree/octree_point_cloud_adjacency.h>
#include <pcl_fot/pcl/octree/impl/octree_point_cloud.hpp>

#ifndef PCL_NO_PRECOMPILE
#include "pcl/instantiated_point_types.h"
PCL_INSTANTIATE(OctreePointCloudAdjacency, PCL_FOT_INSTANTIATED_POINT_TYPES)
#endif
