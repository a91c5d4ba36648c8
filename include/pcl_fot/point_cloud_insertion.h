#pragma once

#include <pcl/point_cloud.h>

#include <pcl_fot/fast_oct_tree.h>

namespace pcl {
namespace fot {

/**
 * Writes the cell of every point of `cloud` into a FastOctTree or FastOccMesh, in the map frame as given
 * (no sensor pose, no ray tracing; see occupancy_mapping.h for scans). Works for any point type with
 * x, y, z. NaN and Inf points, which organised clouds are full of, are skipped and counted.
 */
template <typename MapT, typename PointT>
InsertStats insertPointCloud(MapT& map, const pcl::PointCloud<PointT>& cloud,
                             CellState state = CellState::Occupied) {
  if (cloud.empty()) return {};
  return map.insertPoints(&cloud[0].x, cloud.size(), sizeof(PointT), state);
}

}  // namespace fot
}  // namespace pcl
