#include <pcl_fot/registration/impl/transformation_validation_psi.hpp>

#ifndef PCL_NO_PRECOMPILE
#include <pcl/point_types.h>
#include <pcl/impl/instantiate.hpp>
PCL_INSTANTIATE(TransformationValidationPsi, PCL_XYZ_POINT_TYPES)
#endif
