#include <pcl_fot/impl/octree_point_cloud.hpp>

#ifndef PCL_NO_PRECOMPILE
#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>
PCL_INSTANTIATE(OctreePointCloud, PCL_XYZ_POINT_TYPES)
#endif
