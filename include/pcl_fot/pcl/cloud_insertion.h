#pragma once

#include <vector>

#include <pcl/point_cloud.h>
#include <Eigen/Geometry>

#include <pcl_fot/mapping/scan_insertion.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

/**
 * Writes the cell of every point of `cloud` into a FastOctTree or FastOccMesh, in the map frame as given
 * (no sensor pose, no ray tracing; see insertScan for scans). Works for any point type with x, y, z. NaN and
 * Inf points, which organised clouds are full of, are skipped and counted.
 */
template <typename MapT, typename PointT>
InsertStats insertPointCloud(MapT& map, const pcl::PointCloud<PointT>& cloud,
                             CellState state = CellState::Occupied) {
  if (cloud.empty()) return {};
  return map.insertPoints(&cloud[0].x, cloud.size(), sizeof(PointT), state);
}

/**
 * Inserts a range scan with ray tracing into a FastOctTree or FastOccMesh. The cloud's points are in the
 * sensor frame; `sensor_pose` maps them into the map frame, and its translation is the ray origin. Works
 * for any point type with x, y, z. See insertRays() for the update rules and ScanOptions for the ranges.
 */
template <typename MapT, typename PointT>
ScanStats insertScan(MapT& map, const pcl::PointCloud<PointT>& cloud, const Eigen::Affine3f& sensor_pose,
                     const ScanOptions& options = {}) {
  std::vector<float> xyz(3 * cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f p = sensor_pose * cloud[i].getVector3fMap();
    xyz[3 * i] = p.x();
    xyz[3 * i + 1] = p.y();
    xyz[3 * i + 2] = p.z();
  }
  const Eigen::Vector3f origin = sensor_pose.translation();
  const float sensor[3] = {origin.x(), origin.y(), origin.z()};
  return insertRays(map, sensor, xyz.data(), cloud.size(), 3 * sizeof(float), options);
}

template <typename MapT, typename PointT>
ScanStats insertScan(MapT& map, const pcl::PointCloud<PointT>& cloud, const Eigen::Matrix4f& sensor_pose,
                     const ScanOptions& options = {}) {
  return insertScan(map, cloud, Eigen::Affine3f(sensor_pose), options);
}

/** The pose comes from the cloud's sensor_origin_ and sensor_orientation_ (a PCD file's VIEWPOINT). */
template <typename MapT, typename PointT>
ScanStats insertScan(MapT& map, const pcl::PointCloud<PointT>& cloud, const ScanOptions& options = {}) {
  const Eigen::Affine3f pose =
      Eigen::Translation3f(cloud.sensor_origin_.template head<3>()) * cloud.sensor_orientation_.normalized();
  return insertScan(map, cloud, pose, options);
}

}  // namespace fot
}  // namespace pcl
