#include <pcl_fot/pcl/impl/fast_oct_tree_search.hpp>

#ifndef PCL_NO_PRECOMPILE
#include <pcl/point_types.h>
#include <pcl/impl/instantiate.hpp>
PCL_INSTANTIATE(FastOctTreeSearch, PCL_XYZ_POINT_TYPES)
#endif
