// OctreePointCloudVoxelCentroid for each point type.
#include <pcl_fot/pcl/octree/octree_point_cloud_voxel_centroid.h>
#include <pcl_fot/pcl/octree/impl/octree_point_cloud.hpp>

#ifndef PCL_NO_PRECOMPILE
#include "pcl/instantiated_point_types.h"
PCL_INSTANTIATE(OctreePointCloudVoxelCentroid, PCL_FOT_INSTANTIATED_POINT_TYPES)
#endif
