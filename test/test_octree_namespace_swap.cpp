// Code written for pcl::octree, moved to pcl_fot by changing its namespace: octree_client_code.inc is
// compiled once with `octree` naming pcl::octree and once naming pcl::fot, and both must print the same.
#include <gtest/gtest.h>

#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <pcl/octree/octree.h>
#include <pcl/octree/octree_pointcloud_changedetector.h>
#include <pcl/octree/octree_pointcloud_density.h>
#include <pcl/octree/octree_pointcloud_pointvector.h>
#include <pcl/octree/octree_pointcloud_singlepoint.h>
#include <pcl/octree/octree_pointcloud_voxelcentroid.h>
#include <pcl/octree/octree_search.h>

#include <pcl_fot/pcl/octree/octree.h>

#include "scan_data.h"

namespace with_pcl {
namespace octree = pcl::octree;
#include "octree_client_code.inc"
}  // namespace with_pcl

namespace with_fot {
namespace octree = pcl::fot;
#include "octree_client_code.inc"
}  // namespace with_fot

TEST(OctreeNamespaceSwap, CodeWrittenForPclOctreeRunsTheSameWithPclFot) {
  std::mt19937 rng(5);
  const auto cloud = pcl_fot_test::randomCloud(rng, 600, 4.0f);
  const auto moved = pcl_fot_test::randomCloud(rng, 600, 4.0f);
  const std::string pcl_says = with_pcl::clientRun(cloud, moved),
                    fot_says = with_fot::clientRun(cloud, moved);
  EXPECT_GT(pcl_says.size(), 2000u) << "the client code printed little:\n" << pcl_says;
  EXPECT_EQ(fot_says, pcl_says);
}
