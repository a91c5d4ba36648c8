#pragma once
// The whole public API of pcl_fot. Each header also stands alone; include the ones you use to compile
// faster (the PCL adapters under pcl/ bring in PCL's headers).

// The tree: keys and the cell grid, the node word, the FastOctTree, LineBurstAccess.
#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/cell_grid.h>
#include <pcl_fot/tree/fast_oct_tree.h>
#include <pcl_fot/tree/key.h>
#include <pcl_fot/tree/node_view.h>
#include <pcl_fot/tree/node_word.h>
#include <pcl_fot/tree/tree_coord.h>

// The paper's dense bit grid, the baseline.
#include <pcl_fot/dense/fast_occ_mesh.h>

// Mapping: ray traversal, scan insertion, ray casting.
#include <pcl_fot/mapping/cast_ray.h>
#include <pcl_fot/mapping/ray_traversal.h>
#include <pcl_fot/mapping/scan_insertion.h>

// Search: nearest cells, nearest points.
#include <pcl_fot/search/nearest_cell_search.h>
#include <pcl_fot/search/point_index.h>

// ψ, and the paper's dmap_v method.
#include <pcl_fot/psi/distance_map.h>
#include <pcl_fot/psi/psi.h>

// Files: .fot, OctoMap's .bt and .ot, files for pcl_viewer.
#include <pcl_fot/io/file_io.h>
#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/octomap.h>
#include <pcl_fot/io/voxel_export.h>

// The PCL adapters: clouds in, the pcl::octree look-alikes, the pcl::search drop-in, registration plugins.
#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/pcl/octree/octree.h>
#include <pcl_fot/pcl/registration/correspondence_rejection_psi.h>
#include <pcl_fot/pcl/registration/transformation_validation_psi.h>
#include <pcl_fot/pcl/search/fast_oct_tree_search.h>
