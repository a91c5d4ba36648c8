#pragma once

// The pcl::octree look-alikes, as <pcl/octree/octree.h> offers pcl::octree's.
#include <pcl_fot/pcl/octree/octree_containers.h>
#include <pcl_fot/pcl/octree/octree_point_cloud.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_adjacency.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_change_detector.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_density.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_point_vector.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_search.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_single_point.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_voxel_centroid.h>
