// Maps a few points through the installed library and searches them with the pcl::search drop-in.
#include <iostream>

#include <pcl/point_types.h>
#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/pcl/search/fast_oct_tree_search.h>
#include <pcl_fot/tree/accessor.h>

int main() {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (int i = 0; i < 100; ++i) cloud->push_back(pcl::PointXYZ(0.01f * i, 0.5f, 1.0f));
  pcl::fot::FastOctTree map(0.05);
  pcl::fot::insertPointCloud(map, *cloud);
  pcl::fot::search::FastOctTreeSearch<pcl::PointXYZ> search(0.05);
  search.setInputCloud(cloud);
  pcl::Indices indices;
  std::vector<float> distances;
  search.nearestKSearch(pcl::PointXYZ(0.5f, 0.5f, 1.0f), 1, indices, distances);
  const bool found = indices.at(0) == 50;
  // Made as a KdTree is, behind PCL's interface: the cell edge is picked from the cloud.
  pcl::search::Search<pcl::PointXYZ>::Ptr picked(new pcl::fot::search::FastOctTreeSearch<pcl::PointXYZ>);
  picked->setInputCloud(cloud);
  const bool picked_found =
      picked->nearestKSearch(pcl::PointXYZ(0.5f, 0.5f, 1.0f), 3, indices, distances) == 3 &&
      indices.at(0) == 50;
  std::cout << "occupied cells: " << map.getOccupiedCount() << ", nearest point: " << (found ? 50 : -1)
            << ", with the cell edge picked: " << indices.at(0) << "\n";
  return map.getOccupiedCount() == 20 && found && picked_found ? 0 : 1;
}
