#pragma once
// The point types the library's templates are compiled for: PCL's XYZ types, or the shorter list of the CMake
// option PCL_FOT_POINT_TYPES (the sanitizer and fuzz builds compile only the types their tests use).
#include <pcl/point_types.h>
#include <pcl/impl/instantiate.hpp>

#ifndef PCL_FOT_INSTANTIATED_POINT_TYPES
#define PCL_FOT_INSTANTIATED_POINT_TYPES PCL_XYZ_POINT_TYPES
#endif
