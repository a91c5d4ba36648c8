// PCL's octree tutorials (spatial partitioning and search, spatial change detection), in our own words:
// each body is written once and compiled twice, with pcl::octree's type and with pcl::fot's, and the
// two runs must print the same answers.
#include <gtest/gtest.h>

#include <random>
#include <sstream>
#include <string>

#include <pcl/octree/octree_pointcloud_changedetector.h>
#include <pcl/octree/octree_search.h>

#include <pcl_fot/pcl/octree/octree_point_cloud_change_detector.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_search.h>

#include "scan_data.h"

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace {

/** The search tutorial: a thousand points in a 1024 m cube, 128 m voxels; voxel, k-NN and radius searches. */
template <template <typename...> class OctreeSearch>
std::string searchTutorial(unsigned seed) {
  std::mt19937 rng(seed);
  const Cloud::Ptr cloud = pcl_fot_test::randomCloud(rng, 1000, 1024.0f);
  OctreeSearch<pcl::PointXYZ> octree(128.0f);
  octree.setInputCloud(cloud);
  octree.addPointsFromInputCloud();

  std::uniform_real_distribution<float> u(0.0f, 1024.0f);
  const pcl::PointXYZ query(u(rng), u(rng), u(rng));
  std::ostringstream out;
  pcl::Indices in_voxel;
  if (octree.voxelSearch(query, in_voxel))
    for (const auto i : in_voxel) out << "voxel " << i << "\n";
  pcl::Indices nearest;
  std::vector<float> nearest_distances;
  if (octree.nearestKSearch(query, 10, nearest, nearest_distances) > 0)
    for (std::size_t i = 0; i < nearest.size(); ++i)
      out << "knn " << nearest[i] << " " << nearest_distances[i] << "\n";
  pcl::Indices within;
  std::vector<float> within_distances;
  const float radius = 256.0f * std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
  if (octree.radiusSearch(query, radius, within, within_distances) > 0)
    for (std::size_t i = 0; i < within.size(); ++i)
      out << "radius " << within[i] << " " << within_distances[i] << "\n";
  return out.str();
}

/** The change detection tutorial: two clouds of 128 points in a 64 m cube, 32 m voxels. */
template <template <typename...> class ChangeDetector>
std::string changeTutorial(unsigned seed) {
  std::mt19937 rng(seed);
  ChangeDetector<pcl::PointXYZ> octree(32.0f);
  const Cloud::Ptr before = pcl_fot_test::randomCloud(rng, 128, 64.0f);
  octree.setInputCloud(before);
  octree.addPointsFromInputCloud();
  octree.switchBuffers();
  // The second cloud reaches further, so some of its voxels are new.
  const Cloud::Ptr after = pcl_fot_test::randomCloud(rng, 128, 96.0f);
  octree.setInputCloud(after);
  octree.addPointsFromInputCloud();
  pcl::Indices fresh;
  octree.getPointIndicesFromNewVoxels(fresh);
  std::ostringstream out;
  for (const auto i : fresh)
    out << i << " (" << (*after)[i].x << " " << (*after)[i].y << " " << (*after)[i].z << ")\n";
  return out.str();
}

}  // namespace

TEST(OctreeTutorials, SpatialPartitioningAndSearch) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const std::string ours = searchTutorial<pcl::fot::OctreePointCloudSearch>(seed);
    EXPECT_EQ(searchTutorial<pcl::octree::OctreePointCloudSearch>(seed), ours) << "seed " << seed;
    EXPECT_NE(ours.find("knn"), std::string::npos);
  }
}

TEST(OctreeTutorials, SpatialChangeDetection) {
  std::size_t changes = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const std::string ours = changeTutorial<pcl::fot::OctreePointCloudChangeDetector>(seed);
    EXPECT_EQ(changeTutorial<pcl::octree::OctreePointCloudChangeDetector>(seed), ours) << "seed " << seed;
    changes += !ours.empty();
  }
  EXPECT_GT(changes, 10u);
}
