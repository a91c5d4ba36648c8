#pragma once

#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

namespace pcl_fot_test {

/** The real scans: PCL_FOT_DATA_DIR from the environment, else the directory CMake found. */
inline std::string dataFile(const std::string& name) {
  const char* env = std::getenv("PCL_FOT_DATA_DIR");
  const std::string dir = (env && *env) ? env : PCL_FOT_DATA_DIR;
  return dir + "/" + name;
}

inline const std::vector<std::string>& allScans() {
  static const std::vector<std::string> names = {"kinect_capture0001.pcd", "kinect_capture0002.pcd",
                                                 "kinect_capture0003.pcd", "room_scan1.pcd",
                                                 "room_scan2.pcd",         "terrain_samp11.pcd"};
  return names;
}

/** Loads a real scan or throws, so a missing data directory fails loudly instead of skipping. */
inline pcl::PointCloud<pcl::PointXYZ>::Ptr loadScan(const std::string& name) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  const std::string path = dataFile(name);
  if (pcl::io::loadPCDFile(path, *cloud) != 0 || cloud->empty())
    throw std::runtime_error("cannot read the real scan " + path +
                             "; point PCL_FOT_DATA_DIR at the directory that holds it");
  return cloud;
}

/** n points drawn uniformly from the cube [0, side)³, from rng. */
inline pcl::PointCloud<pcl::PointXYZ>::Ptr randomCloud(std::mt19937& rng, std::size_t n, float side) {
  std::uniform_real_distribution<float> u(0.0f, side);
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (std::size_t i = 0; i < n; ++i) cloud->emplace_back(u(rng), u(rng), u(rng));
  return cloud;
}

inline pcl::PointCloud<pcl::PointXYZ>::Ptr randomCloud(std::size_t n, float side, unsigned seed) {
  std::mt19937 rng(seed);
  return randomCloud(rng, n, side);
}

/** Fills a pcl::octree and its look-alike alike from `cloud`, with dynamic depth if max_per_leaf is not 0. */
template <typename Reference, typename Ours>
void fillBoth(Reference& ref, Ours& ours, const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud,
              std::size_t max_per_leaf = 0) {
  ref.setInputCloud(cloud);
  ours.setInputCloud(cloud);
  if (max_per_leaf) {
    ref.enableDynamicDepth(max_per_leaf);
    ours.enableDynamicDepth(max_per_leaf);
  }
  ref.addPointsFromInputCloud();
  ours.addPointsFromInputCloud();
}

}  // namespace pcl_fot_test
