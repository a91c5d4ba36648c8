#include <pcl_fot/registration/impl/transformation_validation_psi.hpp>

#ifndef PCL_NO_PRECOMPILE
#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>
PCL_INSTANTIATE(TransformationValidationPsi, PCL_XYZ_POINT_TYPES)
#endif
