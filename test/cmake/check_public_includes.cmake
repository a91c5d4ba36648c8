# Fails if a public header includes a private one: a quoted (src/) header, or a detail/ header from a
# header that is not on the list below of those whose templates or inline hot paths need it.
set(allowed
  "pcl_fot/tree/tree_coord.h:pcl_fot/detail/bits.h"
  "pcl_fot/tree/leaf_values.h:pcl_fot/detail/row_pages.h"
  "pcl_fot/dense/fast_occ_mesh.h:pcl_fot/detail/bits.h"
  "pcl_fot/pcl/octree/octree_leaf_table.h:pcl_fot/detail/version_cache.h"
  "pcl_fot/pcl/octree/octree_point_cloud_search.h:pcl_fot/detail/version_cache.h"
  "pcl_fot/pcl/octree/impl/octree_point_cloud_search.hpp:pcl_fot/detail/bits.h"
  "pcl_fot/pcl/search/impl/fast_oct_tree_search.hpp:pcl_fot/detail/cloud_fingerprint.h"
  "pcl_fot/pcl/search/impl/fast_oct_tree_search.hpp:pcl_fot/detail/worker_threads.h"
  "pcl_fot/pcl/registration/impl/transformation_validation_psi.hpp:pcl_fot/detail/cloud_fingerprint.h")
file(GLOB_RECURSE headers RELATIVE "${INCLUDE_DIR}" "${INCLUDE_DIR}/pcl_fot/*.h" "${INCLUDE_DIR}/pcl_fot/*.hpp")
set(failures "")
foreach(header ${headers})
  if(header MATCHES "^pcl_fot/detail/")
    continue()
  endif()
  file(STRINGS "${INCLUDE_DIR}/${header}" lines REGEX "^#include")
  foreach(line ${lines})
    if(line MATCHES "^#include \"")
      string(APPEND failures "  ${header}: ${line}\n")
    elseif(line MATCHES "^#include <(pcl_fot/detail/[^>]*)>")
      list(FIND allowed "${header}:${CMAKE_MATCH_1}" at)
      if(at EQUAL -1)
        string(APPEND failures "  ${header}: ${line}\n")
      endif()
    endif()
  endforeach()
endforeach()
if(failures)
  message(FATAL_ERROR "public headers include private ones:\n${failures}")
endif()
message(STATUS "${CMAKE_CURRENT_LIST_FILE}: the public headers include no private header")
