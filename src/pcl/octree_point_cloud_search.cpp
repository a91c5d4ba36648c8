#include <pcl_fot/pcl/impl/octree_point_cloud_search.hpp>

#ifndef PCL_NO_PRECOMPILE
#include <pcl/point_types.h>
#include <pcl/impl/instantiate.hpp>
PCL_INSTANTIATE(OctreePointCloudSearch, PCL_XYZ_POINT_TYPES)
#endif
