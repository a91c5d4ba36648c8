#pragma once

#include <limits>

#include <pcl/common/common.h>
#include <pcl/common/point_tests.h>
#include <pcl/console/print.h>

#include <pcl_fot/pcl/octree/octree_point_cloud.h>

namespace pcl {
namespace fot {

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::OctreePointCloud(const double resolution_arg)
    : table_(resolution_arg, kHoldsLeaves) {}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::setInputCloud(
    const PointCloudConstPtr& cloud_arg, const IndicesConstPtr& indices_arg) {
  input_ = cloud_arg;
  indices_ = indices_arg;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::setResolution(double resolution_arg) {
  table_.setResolution(resolution_arg);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::LeafNode*
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::slotNode(Slot slot, bool created) {
  if constexpr (kHoldsLeaves) nodes_.reset(slot, created);
  return node(slot);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::LeafNode*
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::createLeaf(const octree::OctreeKey& key) {
  bool created;
  const Slot slot = table_.createLeaf(key, created);
  return slotNode(slot, created);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
LeafContainerT* OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::createLeaf(uindex_t idx_x_arg,
                                                                                       uindex_t idx_y_arg,
                                                                                       uindex_t idx_z_arg) {
  if (!table_.boxDefined()) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::createLeaf] No bounding box is defined yet; no leaf is created.\n");
    return nullptr;
  }
  if (((idx_x_arg | idx_y_arg | idx_z_arg) >> getTreeDepth()) != 0) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::createLeaf] The key (%u, %u, %u) lies beyond the bounding box "
        "(depth %u); no leaf is created.\n",
        idx_x_arg, idx_y_arg, idx_z_arg, getTreeDepth());
    return nullptr;
  }
  return &createLeaf(octree::OctreeKey(idx_x_arg, idx_y_arg, idx_z_arg))->getContainer();
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
LeafContainerT* OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::findLeaf(
    uindex_t idx_x_arg, uindex_t idx_y_arg, uindex_t idx_z_arg) const {
  if (!table_.boxDefined() || ((idx_x_arg | idx_y_arg | idx_z_arg) >> getTreeDepth()) != 0) return nullptr;
  LeafNode* leaf = findLeaf(octree::OctreeKey(idx_x_arg, idx_y_arg, idx_z_arg));
  return leaf ? &leaf->getContainer() : nullptr;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::expandLeaf(const LeafId& id, Slot slot) {
  Indices indices;
  nodes_.appendIndices(slot, indices);
  table_.eraseLeaf(id);
  nodes_.drop(slot);
  for (const index_t index : indices) {
    const PointT& p = (*input_)[index];
    const Key k = table_.pclKeyToTreeKey(table_.pclKey(p.x, p.y, p.z));
    bool created;
    const Slot child = table_.leafOfCube(table_.cubeOf(k, id.level - 1), created);
    slotNode(child, created)->getContainer().addPointIndex(index);
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::addPointIdx(uindex_t point_idx_arg) {
  const PointT& point = (*input_)[point_idx_arg];
  if (!isFinite(point)) {
    PCL_ERROR("[pcl::fot::OctreePointCloud] Point %zu is not finite; it is not added.\n",
              static_cast<std::size_t>(point_idx_arg));
    return;
  }
  if (!table_.adoptBoundingBoxToPoint(point.x, point.y, point.z)) return;
  const Key k = table_.pclKeyToTreeKey(table_.pclKey(point.x, point.y, point.z));
  LeafId id;
  bool created;
  Slot slot = table_.leafForPoint(k, id, created);
  LeafNode* leaf = slotNode(slot, created);
  if constexpr (kHoldsLeaves) {
    if (table_.maxObjsPerLeaf() != 0) {
      while (id.level > 0 && (*leaf)->getSize() >= table_.maxObjsPerLeaf()) {
        expandLeaf(id, slot);
        slot = table_.leafForPoint(k, id, created);
        leaf = slotNode(slot, created);
      }
      table_.markCell(k);  // a shallow leaf's cube keeps every point's cell
    }
  }
  addToLeaf(leaf->getContainer(), static_cast<index_t>(point_idx_arg));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::setOccupiedVoxelAtPoint(
    const PointT& point_arg) {
  if (!isFinite(point_arg)) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::setOccupiedVoxelAtPoint] The point is not finite; it is not added.\n");
    return;
  }
  if (!adoptBoundingBoxToPoint(point_arg.x, point_arg.y, point_arg.z)) return;
  createLeaf(pclKey(point_arg.x, point_arg.y, point_arg.z));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::setOccupiedVoxelsAtPointsFromCloud(
    PointCloudPtr cloud_arg) {
  for (const auto& p : *cloud_arg)
    if (isFinite(p)) setOccupiedVoxelAtPoint(p);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::addPointsFromInputCloud() {
  if (!input_) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::addPointsFromInputCloud] No input cloud.\n");
    return;
  }
  Indices points;  // the finite points of the input, in its order
  if (indices_) {
    points.reserve(indices_->size());
    for (const auto index : *indices_) {
      if (index < 0 || static_cast<std::size_t>(index) >= input_->size()) {
        PCL_ERROR("[pcl::fot::OctreePointCloud::addPointsFromInputCloud] Index %d is outside the cloud.\n",
                  index);
        continue;
      }
      if (isFinite((*input_)[index])) points.push_back(index);
    }
  } else {
    points.reserve(input_->size());
    for (std::size_t i = 0; i < input_->size(); ++i)
      if (isFinite((*input_)[i])) points.push_back(static_cast<index_t>(i));
  }
  std::size_t next = 0;
  if constexpr (kHoldsLeaves) {
    if (table_.maxObjsPerLeaf() == 0 && addsPointsInBulk()) {
      // Until the first leaf exists, the box grows as it does for an empty octree (PCL keeps its old roots).
      while (next < points.size() && getLeafCount() == 0) addPointIdx(static_cast<uindex_t>(points[next++]));
      addInBulk(points, next);
    }
  }
  for (; next < points.size(); ++next) addPointIdx(static_cast<uindex_t>(points[next]));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::addInBulk(Indices& points,
                                                                           std::size_t& next) {
  std::vector<Key> keys;
  keys.reserve(points.size() - next);
  std::size_t kept = 0;
  for (; next < points.size(); ++next) {
    const PointT& p = (*input_)[points[next]];
    if (!table_.adoptBoundingBoxToPoint(p.x, p.y, p.z)) continue;
    keys.push_back(table_.pclKeyToTreeKey(table_.pclKey(p.x, p.y, p.z)));
    points[kept++] = points[next];
  }
  if constexpr (decltype(nodes_)::kRuns) nodes_.reserveRuns(keys.size());
  table_.leavesOfKeys(keys, [&](Slot slot, bool created, const std::uint32_t* first,
                                const std::uint32_t* last) {
    // A new leaf of point indices gets them as a run, in the cloud's order, as addPointIndex would add them.
    if constexpr (decltype(nodes_)::kRuns) {
      if (created) {
        nodes_.addRun(slot, first, last, points.data());
        return;
      }
    }
    LeafContainerT& leaf = slotNode(slot, created)->getContainer();
    if constexpr (std::is_base_of_v<OctreeContainerPointIndices, LeafContainerT>)  // one allocation a leaf
      leaf.getPointIndicesVector().reserve(leaf.getSize() + static_cast<std::size_t>(last - first));
    for (; first != last; ++first) addToLeaf(leaf, points[*first]);
  });
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::addPointFromCloud(uindex_t point_idx_arg,
                                                                                   IndicesPtr indices_arg) {
  if (!input_ || point_idx_arg >= input_->size()) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::addPointFromCloud] Index %zu is outside the input cloud.\n",
              static_cast<std::size_t>(point_idx_arg));
    return;
  }
  addPointIdx(point_idx_arg);
  if (indices_arg) indices_arg->push_back(static_cast<index_t>(point_idx_arg));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::addPointToCloud(const PointT& point_arg,
                                                                                 PointCloudPtr cloud_arg) {
  if (!cloud_arg || cloud_arg != input_) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::addPointToCloud] The cloud must be the input cloud.\n");
    return;
  }
  cloud_arg->push_back(point_arg);
  addPointIdx(static_cast<uindex_t>(cloud_arg->size() - 1));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::addPointToCloud(const PointT& point_arg,
                                                                                 PointCloudPtr cloud_arg,
                                                                                 IndicesPtr indices_arg) {
  if (!cloud_arg || cloud_arg != input_ || !indices_arg || indices_arg != indices_) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::addPointToCloud] The cloud and indices must be the input's.\n");
    return;
  }
  cloud_arg->push_back(point_arg);
  indices_arg->push_back(static_cast<index_t>(cloud_arg->size()) - 1);
  addPointIdx(static_cast<uindex_t>(cloud_arg->size() - 1));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
bool OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::isVoxelOccupiedAtPoint(
    const PointT& point_arg) const {
  return slotAtPoint(point_arg) != kNoLeaf;  // asking gives no leaf of runs its node
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
LeafContainerT* OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::findLeafAtPoint(
    const PointT& point_arg) const {
  LeafNode* leaf = node(slotAtPoint(point_arg));
  return leaf ? leaf->getContainerPtr() : nullptr;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
bool OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::isVoxelOccupiedAtPoint(
    const double point_x_arg, const double point_y_arg, const double point_z_arg) const {
  PointT point;  // through PointT's floats, as PCL does
  point.x = point_x_arg;
  point.y = point_y_arg;
  point.z = point_z_arg;
  return isVoxelOccupiedAtPoint(point);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
bool OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::isVoxelOccupiedAtPoint(
    const index_t& point_idx_arg) const {
  if (!input_ || point_idx_arg < 0 || static_cast<std::size_t>(point_idx_arg) >= input_->size()) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::isVoxelOccupiedAtPoint] Index %d is not in the input cloud.\n",
              point_idx_arg);
    return false;
  }
  return isVoxelOccupiedAtPoint((*input_)[point_idx_arg]);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::deleteVoxelAtPoint(const PointT& point_arg) {
  if (!isPointWithinBoundingBox(point_arg.x, point_arg.y, point_arg.z)) return;
  const octree::OctreeKey key = pclKey(point_arg.x, point_arg.y, point_arg.z);
  removeLeaf(key.x, key.y, key.z);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::deleteVoxelAtPoint(
    const index_t& point_idx_arg) {
  if (!input_ || point_idx_arg < 0 || static_cast<std::size_t>(point_idx_arg) >= input_->size()) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::deleteVoxelAtPoint] Index %d is not in the input cloud.\n",
              point_idx_arg);
    return;
  }
  deleteVoxelAtPoint((*input_)[point_idx_arg]);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getOccupiedVoxelCenters(
    AlignedPointTVector& voxel_center_list_arg) const {
  voxel_center_list_arg.clear();
  for (auto it = leaf_depth_begin(); it != leaf_depth_end(); ++it) {
    // As PCL: a shallow leaf's key, of its own depth, is taken as a voxel's.
    PointT center;
    pclKeyToCenter(it.getCurrentOctreeKey(), center);
    voxel_center_list_arg.push_back(center);
  }
  return static_cast<uindex_t>(voxel_center_list_arg.size());
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::NodeIterator
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::fixed_depth_begin(
    uindex_t fixed_depth_arg) const {
  if (fixed_depth_arg > getTreeDepth()) {
    PCL_WARN(
        "[pcl::fot::OctreePointCloud::fixed_depth_begin] Depth %u is deeper than the octree (depth %u).\n",
        fixed_depth_arg, getTreeDepth());
    return end();
  }
  return NodeIterator(this, false, NodeIterator::Stops::OneDepth, fixed_depth_arg);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::defineBoundingBox() {
  if (!input_) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::defineBoundingBox] No input cloud.\n");
    return;
  }
  PointT lo, hi;
  pcl::getMinMax3D(*input_, lo, hi);
  const float min_value = std::numeric_limits<float>::epsilon() * 512.0f;
  defineBoundingBox(lo.x, lo.y, lo.z, hi.x + min_value, hi.y + min_value, hi.z + min_value);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::defineBoundingBox(
    const double min_x_arg, const double min_y_arg, const double min_z_arg, const double max_x_arg,
    const double max_y_arg, const double max_z_arg) {
  const double lo[3] = {min_x_arg, min_y_arg, min_z_arg}, hi[3] = {max_x_arg, max_y_arg, max_z_arg};
  table_.defineBoundingBox(lo, hi);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::defineBoundingBox(const double max_x_arg,
                                                                                   const double max_y_arg,
                                                                                   const double max_z_arg) {
  defineBoundingBox(std::min(0.0, max_x_arg), std::min(0.0, max_y_arg), std::min(0.0, max_z_arg),
                    std::max(0.0, max_x_arg), std::max(0.0, max_y_arg), std::max(0.0, max_z_arg));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::defineBoundingBox(const double cubeLen_arg) {
  defineBoundingBox(cubeLen_arg, cubeLen_arg, cubeLen_arg);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getBoundingBox(
    double& min_x_arg, double& min_y_arg, double& min_z_arg, double& max_x_arg, double& max_y_arg,
    double& max_z_arg) const {
  double lo[3], hi[3];
  table_.getBoundingBox(lo, hi);
  min_x_arg = lo[0];
  min_y_arg = lo[1];
  min_z_arg = lo[2];
  max_x_arg = hi[0];
  max_y_arg = hi[1];
  max_z_arg = hi[2];
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getApproxIntersectedVoxelCentersBySegment(
    const Eigen::Vector3f& origin, const Eigen::Vector3f& end, AlignedPointTVector& voxel_center_list,
    float precision) {
  table_.walkSegment(origin, end, precision, [&](const octree::OctreeKey& key) {
    PointT center;
    pclKeyToCenter(key, center);
    voxel_center_list.push_back(center);
  });
  return static_cast<uindex_t>(voxel_center_list.size());
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getIntersectedVoxelCenters(
    Eigen::Vector3f origin, Eigen::Vector3f direction, AlignedPointTVector& voxel_center_list,
    uindex_t max_voxel_count) const {
  voxel_center_list.clear();
  table_.walkRay(origin, direction, [&](const octree::OctreeKey& key) {
    PointT center;
    pclKeyToCenter(key, center);
    voxel_center_list.push_back(center);
    return max_voxel_count == 0 || voxel_center_list.size() < max_voxel_count;
  });
  return static_cast<uindex_t>(voxel_center_list.size());
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getIntersectedVoxelIndices(
    Eigen::Vector3f origin, Eigen::Vector3f direction, Indices& k_indices, uindex_t max_voxel_count) const {
  k_indices.clear();
  uindex_t voxels = 0;
  Slot previous = kNoLeaf;  // a shallow leaf spans several cells in a row
  table_.walkRay(origin, direction, [&](const octree::OctreeKey& key) {
    const Slot leaf = findSlot(key);
    if (leaf == kNoLeaf || leaf == previous) return true;
    previous = leaf;
    appendLeafIndices(leaf, k_indices);
    return max_voxel_count == 0 || ++voxels < max_voxel_count;
  });
  return static_cast<uindex_t>(k_indices.size());
}

}  // namespace fot
}  // namespace pcl

// The look-alikes' leaves: point indices (OctreePointCloud, PointVector, Search, ChangeDetector), none
// (Occupancy), one index (SinglePoint), a count (Density), a sum (VoxelCentroid), neighbours (Adjacency).
#define PCL_INSTANTIATE_OctreePointCloud(T) template class PCL_EXPORTS pcl::fot::OctreePointCloud<T>;
#define PCL_INSTANTIATE_OctreePointCloudOccupancy(T) \
  template class PCL_EXPORTS pcl::fot::OctreePointCloud<T, pcl::fot::OctreeContainerEmpty>;
#define PCL_INSTANTIATE_OctreePointCloudSinglePoint(T) \
  template class PCL_EXPORTS pcl::fot::OctreePointCloud<T, pcl::fot::OctreeContainerPointIndex>;
#define PCL_INSTANTIATE_OctreePointCloudDensity(T) \
  template class PCL_EXPORTS pcl::fot::OctreePointCloud<T, pcl::fot::OctreePointCloudDensityContainer>;
#define PCL_INSTANTIATE_OctreePointCloudVoxelCentroid(T) \
  template class PCL_EXPORTS                             \
      pcl::fot::OctreePointCloud<T, pcl::fot::OctreePointCloudVoxelCentroidContainer<T>>;
#define PCL_INSTANTIATE_OctreePointCloudAdjacency(T) \
  template class PCL_EXPORTS pcl::fot::OctreePointCloud<T, pcl::fot::OctreePointCloudAdjacencyContainer<T>>;
