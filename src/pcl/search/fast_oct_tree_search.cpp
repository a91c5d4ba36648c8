// FastOctTreeSearch for each point type.
#include <pcl_fot/pcl/search/fast_oct_tree_search.h>
#include <pcl_fot/pcl/search/impl/fast_oct_tree_search.hpp>

#ifndef PCL_NO_PRECOMPILE
#include "pcl/instantiated_point_types.h"
PCL_INSTANTIATE(FastOctTreeSearch, PCL_FOT_INSTANTIATED_POINT_TYPES)
#endif
