#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include <pcl/common/common.h>
#include <pcl/common/point_tests.h>
#include <pcl/console/print.h>

#include <pcl_fot/mapping/ray_traversal.h>
#include <pcl_fot/pcl/octree/octree_point_cloud.h>
#include <pcl_fot/tree/accessor.h>

namespace pcl {
namespace fot {
namespace detail {

/** The deepest box the adapter follows PCL to: 2^29 cells per axis keeps tree keys in range. */
constexpr uindex_t kMaxPclDepth = 29;

}  // namespace detail

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::OctreePointCloud(const double resolution_arg)
    : resolution_(resolution_arg), tree_(resolution_arg) {
  max_[0] = max_[1] = max_[2] = resolution_arg;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::setInputCloud(
    const PointCloudConstPtr& cloud_arg, const IndicesConstPtr& indices_arg) {
  input_ = cloud_arg;
  indices_ = indices_arg;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::setResolution(double resolution_arg) {
  if (getLeafCount() != 0) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::setResolution] The octree must be empty to change its resolution.\n");
    return;
  }
  const std::string why = CellGrid::whyInvalid(resolution_arg, 0.0, 0.0, 0.0);
  if (!why.empty()) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::setResolution] Refused: %s.\n", why.c_str());
    return;
  }
  resolution_ = resolution_arg;
  tree_ = FastOctTree(resolution_arg);
  getKeyBitSize();
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
octree::OctreeKey OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::pclKey(double x, double y,
                                                                                     double z) const {
  // A point just inside the box's far face can round to one voxel past it; pcl::octree asserts there.
  const uindex_t last = static_cast<uindex_t>((std::uint64_t(1) << depth_) - 1);
  return octree::OctreeKey(std::min(static_cast<uindex_t>((x - min_[0]) / resolution_), last),
                           std::min(static_cast<uindex_t>((y - min_[1]) / resolution_), last),
                           std::min(static_cast<uindex_t>((z - min_[2]) / resolution_), last));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::pclKeyToCenter(const octree::OctreeKey& key,
                                                                                PointT& point) const {
  point.x = static_cast<float>((static_cast<double>(key.x) + 0.5f) * resolution_ + min_[0]);
  point.y = static_cast<float>((static_cast<double>(key.y) + 0.5f) * resolution_ + min_[1]);
  point.z = static_cast<float>((static_cast<double>(key.z) + 0.5f) * resolution_ + min_[2]);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::voxelCenter(const octree::OctreeKey& key,
                                                                             uindex_t depth,
                                                                             PointT& point) const {
  const double side = resolution_ * static_cast<double>(std::uint64_t(1) << (depth_ - depth));
  point.x = static_cast<float>((static_cast<double>(key.x) + 0.5f) * side + min_[0]);
  point.y = static_cast<float>((static_cast<double>(key.y) + 0.5f) * side + min_[1]);
  point.z = static_cast<float>((static_cast<double>(key.z) + 0.5f) * side + min_[2]);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
OctreeNode* OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::NodeIterator::getCurrentOctreeNode()
    const {
  if (node_.leaf) return tree_->leafAt(node_.key, node_.depth);
  static BranchNode branch;  // branches hold nothing here; one node tells their type
  return &branch;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getKeyBitSize() {
  // PCL's arithmetic, step for step, so that the box comes out bit for bit the same.
  const float min_value = std::numeric_limits<float>::epsilon();
  uindex_t max_voxels = 2;
  for (int a = 0; a < 3; ++a)
    max_voxels =
        std::max(max_voxels, static_cast<uindex_t>(std::ceil((max_[a] - min_[a] - min_value) / resolution_)));
  depth_ = std::max<uindex_t>(
      std::min<uindex_t>(octree::OctreeKey::maxDepth, std::ceil(std::log2(max_voxels) - min_value)), 0);
  const double side = static_cast<double>(std::uint64_t(1) << depth_) * resolution_;
  for (int a = 0; a < 3; ++a) {
    if (getLeafCount() == 0) {
      const double oversize = (side - (max_[a] - min_[a])) / 2.0;
      if (oversize > min_value) {
        min_[a] -= oversize;
        max_[a] += oversize;
      }
    } else {
      max_[a] = min_[a] + side;
    }
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
bool OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::adoptBoundingBoxToPoint(double x, double y,
                                                                                         double z) {
  const float min_value = std::numeric_limits<float>::epsilon();
  const double p[3] = {x, y, z};
  // A point that does not fit leaves the box as it was, not grown part of the way.
  const auto box = std::make_tuple(std::array<double, 3>{min_[0], min_[1], min_[2]},
                                   std::array<double, 3>{max_[0], max_[1], max_[2]}, depth_, offset_);
  const std::size_t phantoms = phantoms_.size();
  while (true) {
    bool lower[3], upper[3];
    for (int a = 0; a < 3; ++a) {
      lower[a] = p[a] < min_[a];
      upper[a] = p[a] >= max_[a];
    }
    const bool violated = lower[0] || lower[1] || lower[2] || upper[0] || upper[1] || upper[2];
    if (bounding_box_defined_ && !violated) return true;
    if (!bounding_box_defined_) {
      // The first point: a box of ±res/2 around it.
      for (int a = 0; a < 3; ++a) {
        min_[a] = p[a] - resolution_ / 2;
        max_[a] = p[a] + resolution_ / 2;
      }
      getKeyBitSize();
      offset_ = {0, 0, 0};
      phantoms_.clear();
      bounding_box_defined_ = true;
      continue;
    }
    if (depth_ >= detail::kMaxPclDepth) {
      PCL_ERROR(
          "[pcl::fot::OctreePointCloud] The point (%g, %g, %g) would grow the octree beyond 2^%u cells per "
          "axis; it is not added.\n",
          x, y, z, detail::kMaxPclDepth);
      const auto& [lo, hi, depth, offset] = box;
      std::copy(lo.begin(), lo.end(), min_);
      std::copy(hi.begin(), hi.end(), max_);
      depth_ = depth;
      offset_ = offset;
      phantoms_.resize(phantoms);
      return false;
    }
    // A new root: the box doubles, downwards on every axis the point does not exceed upwards.
    if (getLeafCount() == 0)  // PCL keeps the empty old root as a branch
      phantoms_.push_back({Key{offset_[0], offset_[1], offset_[2]}, depth_});
    const double side = static_cast<double>(std::uint64_t(1) << depth_) * resolution_;
    for (int a = 0; a < 3; ++a)
      if (!upper[a]) {
        min_[a] -= side;
        offset_[a] -= std::int32_t(1) << depth_;
      }
    ++depth_;
    const double new_side = static_cast<double>(std::uint64_t(1) << depth_) * resolution_ - min_value;
    for (int a = 0; a < 3; ++a) max_[a] = min_[a] + new_side;
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::LeafId
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::cubeOf(const Key& k, std::uint32_t level) const {
  const auto align = [&](std::int32_t v, std::int32_t offset) {
    return std::int32_t(((std::uint32_t(v - offset) >> level) << level) + std::uint32_t(offset));
  };
  return LeafId{Key{align(k.x, offset_[0]), align(k.y, offset_[1]), align(k.z, offset_[2])}, level};
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
bool OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::cubeHasContent(const LeafId& cube) const {
  const std::int32_t last = std::int32_t((std::int64_t(1) << cube.level) - 1);
  const Key hi{cube.corner.x + last, cube.corner.y + last, cube.corner.z + last};
  for (const Phantom& ph : phantoms_)
    if (ph.level <= cube.level && ph.min.x >= cube.corner.x && ph.min.x <= hi.x &&
        ph.min.y >= cube.corner.y && ph.min.y <= hi.y && ph.min.z >= cube.corner.z && ph.min.z <= hi.z)
      return true;
  bool occupied = false;
  tree_.forEachRegionInBox(cube.corner, hi, [&](const Region& r) {
    occupied = r.state == CellState::Occupied;
    return !occupied;
  });
  return occupied;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::LeafNode*
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::leafOnPath(const Key& k, LeafId& id) const {
  if (max_objs_per_leaf_ == 0) {
    id = LeafId{k, 0};
    const auto it = leaves_.find(id);
    return it == leaves_.end() ? nullptr : &it->second;
  }
  // PCL's descent: the root is a branch; below it, the first leaf, or the first node missing.
  for (std::uint32_t level = depth_ - 1;; --level) {
    id = cubeOf(k, level);
    const auto it = leaves_.find(id);
    if (it != leaves_.end()) return &it->second;
    if (level == 0 || !cubeHasContent(id)) return nullptr;
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::LeafNode*
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::createLeaf(const octree::OctreeKey& key) {
  const Key k = pclKeyToTreeKey(key);
  LeafId id;
  LeafNode* leaf = createLeafAt(k, id);
  if (max_objs_per_leaf_ != 0) tree_.setCell(k, CellState::Occupied);  // see createLeafAt
  return leaf;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::LeafNode*
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::createLeafAt(const Key& k, LeafId& id) {
  ++version_;
  if constexpr (!kHoldsLeaves) {
    tree_.setCell(k, CellState::Occupied);
    id = LeafId{k, 0};
    return leafAt(
        octree::OctreeKey(uindex_t(k.x - offset_[0]), uindex_t(k.y - offset_[1]), uindex_t(k.z - offset_[2])),
        depth_);
  } else {
    if (max_objs_per_leaf_ == 0) {
      id = LeafId{k, 0};
      if (last_.leaf && last_.id == id) return last_.leaf;
      const auto [it, inserted] = leaves_.try_emplace(id);
      if (inserted) tree_.setCell(k, CellState::Occupied);
      last_.id = id;
      last_.leaf = &it->second;
      return &it->second;
    }
    // The caller marks the cell once the point is in its leaf: a leaf about to split must not see it.
    LeafNode* leaf = leafOnPath(k, id);
    return leaf ? leaf : &leaves_.try_emplace(id).first->second;
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::LeafNode*
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::findLeaf(const octree::OctreeKey& key) const {
  if constexpr (!kHoldsLeaves) {
    return leafAt(key, depth_);
  } else {
    LeafId id;
    return leafOnPath(pclKeyToTreeKey(key), id);
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::LeafNode*
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::leafAt(const octree::OctreeKey& key,
                                                                   uindex_t depth) const {
  const std::uint32_t level = depth_ - depth;
  const Key corner = pclKeyToTreeKey(octree::OctreeKey(key.x << level, key.y << level, key.z << level));
  if constexpr (!kHoldsLeaves) {
    // Occupancy leaves hold nothing: every one answers with the same empty node.
    static LeafNode empty_leaf;
    return level == 0 && tree_.getCell(corner) == CellState::Occupied ? &empty_leaf : nullptr;
  } else {
    const auto it = leaves_.find(LeafId{corner, level});
    return it == leaves_.end() ? nullptr : &it->second;
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
const typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::LeafNode*
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::approxLeaf(const PointT& point) const {
  const auto branches = branchIndex();
  octree::OctreeKey key(0, 0, 0);
  std::uint8_t children = branches->at(cubeOf(pclKeyToTreeKey(key), depth_));
  for (uindex_t depth = 1; depth <= depth_; ++depth) {
    double nearest = std::numeric_limits<double>::max();
    octree::OctreeKey nearest_key;
    for (unsigned c = 0; c < 8; ++c) {
      if (!(children >> c & 1u)) continue;
      const octree::OctreeKey child(key.x << 1 | (c >> 2 & 1u), key.y << 1 | (c >> 1 & 1u),
                                    key.z << 1 | (c & 1u));
      PointT center;
      voxelCenter(child, depth, center);
      const double d = (center.getVector3fMap() - point.getVector3fMap()).squaredNorm();  // in float, as PCL
      if (d >= nearest) continue;
      nearest = d;
      nearest_key = child;
    }
    if (nearest == std::numeric_limits<double>::max()) return nullptr;  // an empty old root: PCL asserts
    const std::uint32_t level = depth_ - depth;
    const auto it =
        branches->find(LeafId{pclKeyToTreeKey(octree::OctreeKey(
                                  nearest_key.x << level, nearest_key.y << level, nearest_key.z << level)),
                              level});
    if (it == branches->end()) return leafAt(nearest_key, depth);
    key = nearest_key;
    children = it->second;
  }
  return nullptr;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::expandLeaf(const LeafId& id) {
  const auto it = leaves_.find(id);
  Indices indices;
  it->second.getContainer().getPointIndices(indices);
  leaves_.erase(it);
  for (const index_t index : indices) {
    const PointT& p = (*input_)[index];
    const Key k = pclKeyToTreeKey(pclKey(p.x, p.y, p.z));
    leaves_.try_emplace(cubeOf(k, id.level - 1)).first->second.getContainer().addPointIndex(index);
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
  if (!adoptBoundingBoxToPoint(point.x, point.y, point.z)) return;
  const Key k = pclKeyToTreeKey(pclKey(point.x, point.y, point.z));
  LeafId id;
  LeafNode* leaf = createLeafAt(k, id);
  if constexpr (kHoldsLeaves) {
    if (max_objs_per_leaf_ != 0) {
      while (id.level > 0 && (*leaf)->getSize() >= max_objs_per_leaf_) {
        expandLeaf(id);
        leaf = createLeafAt(k, id);
      }
      tree_.setCell(k, CellState::Occupied);  // a shallow leaf's cube keeps every point's cell
    }
  }
  (*leaf)->addPointIndex(static_cast<index_t>(point_idx_arg));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::enableDynamicDepth(
    std::size_t maxObjsPerLeaf) {
  if (getLeafCount() != 0) {
    PCL_ERROR("[pcl::fot::OctreePointCloud::enableDynamicDepth] The octree must be empty.\n");
    return;
  }
  max_objs_per_leaf_ = maxObjsPerLeaf;
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
  if (indices_) {
    for (const auto index : *indices_) {
      if (index < 0 || static_cast<std::size_t>(index) >= input_->size()) {
        PCL_ERROR("[pcl::fot::OctreePointCloud::addPointsFromInputCloud] Index %d is outside the cloud.\n",
                  index);
        continue;
      }
      if (isFinite((*input_)[index])) addPointIdx(static_cast<uindex_t>(index));
    }
    return;
  }
  for (std::size_t i = 0; i < input_->size(); ++i)
    if (isFinite((*input_)[i])) addPointIdx(static_cast<uindex_t>(i));
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
  return findLeafAtPoint(point_arg) != nullptr;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
LeafContainerT* OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::findLeafAtPoint(
    const PointT& point_arg) const {
  if (!isPointWithinBoundingBox(point_arg.x, point_arg.y, point_arg.z)) return nullptr;
  LeafNode* leaf = findLeaf(pclKey(point_arg.x, point_arg.y, point_arg.z));
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
bool OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::existLeaf(uindex_t idx_x_arg,
                                                                           uindex_t idx_y_arg,
                                                                           uindex_t idx_z_arg) const {
  if (((idx_x_arg | idx_y_arg | idx_z_arg) >> depth_) != 0) return false;
  return findLeaf(octree::OctreeKey(idx_x_arg, idx_y_arg, idx_z_arg)) != nullptr;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::removeLeaf(uindex_t idx_x_arg,
                                                                            uindex_t idx_y_arg,
                                                                            uindex_t idx_z_arg) {
  if (((idx_x_arg | idx_y_arg | idx_z_arg) >> depth_) != 0) return;
  const Key target = pclKeyToTreeKey(octree::OctreeKey(idx_x_arg, idx_y_arg, idx_z_arg));
  ++version_;
  if constexpr (kHoldsLeaves) {
    // The first leaf on the path goes, with every cell of its cube.
    LeafId id;
    if (leafOnPath(target, id)) {
      const std::int32_t last = std::int32_t((std::int64_t(1) << id.level) - 1);
      last_.leaf = nullptr;
      leaves_.erase(id);
      tree_.setBox(id.corner, Key{id.corner.x + last, id.corner.y + last, id.corner.z + last},
                   CellState::Unknown);
    }
  } else {
    tree_.eraseCell(target);
  }
  // PCL prunes the branches left without children on the way to the deleted voxel. Empty old roots nest,
  // so the smallest goes first, and each larger one only once nothing is left inside it.
  std::sort(phantoms_.begin(), phantoms_.end(),
            [](const Phantom& a, const Phantom& b) { return a.level < b.level; });
  while (!phantoms_.empty()) {
    const Phantom& ph = phantoms_.front();
    const std::int32_t last = std::int32_t((std::int64_t(1) << ph.level) - 1);
    const Key hi{ph.min.x + last, ph.min.y + last, ph.min.z + last};
    const bool on_path = target.x >= ph.min.x && target.x <= hi.x && target.y >= ph.min.y &&
                         target.y <= hi.y && target.z >= ph.min.z && target.z <= hi.z;
    bool holds_voxels = false;
    if (on_path)
      tree_.forEachRegionInBox(ph.min, hi, [&](const Region& r) {
        holds_voxels = r.state == CellState::Occupied;
        return !holds_voxels;
      });
    if (!on_path || holds_voxels) break;
    phantoms_.erase(phantoms_.begin());
  }
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
std::shared_ptr<const typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::BranchIndex>
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::branchIndex() const {
  return branch_cache_.get(version_, [&] { return buildBranchIndex(); });
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
std::shared_ptr<const typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::BranchIndex>
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::buildBranchIndex() const {
  auto index = std::make_shared<BranchIndex>();
  const LeafId root = cubeOf(pclKeyToTreeKey(octree::OctreeKey(0, 0, 0)), depth_);
  index->emplace(root, 0);
  // Each node marks itself in its parent; a parent met before already has its ancestors marked.
  const auto addNode = [&](LeafId node) {
    for (std::uint32_t level = node.level + 1; level <= depth_; ++level) {
      const LeafId parent = cubeOf(node.corner, level);
      const auto bit = [&](std::int32_t v, std::int32_t offset) {
        return (std::uint32_t(v - offset) >> node.level) & 1u;
      };
      const unsigned child = bit(node.corner.x, offset_[0]) << 2 | bit(node.corner.y, offset_[1]) << 1 |
                             bit(node.corner.z, offset_[2]);
      const auto [it, inserted] = index->try_emplace(parent, 0);
      it->second |= std::uint8_t(1u << child);
      if (!inserted) return;
      node = parent;
    }
  };
  if constexpr (kHoldsLeaves)
    for (const auto& leaf : leaves_) addNode(leaf.first);
  else
    tree_.forEachCell(CellState::Occupied, [&](const Key& k) { addNode(LeafId{k, 0}); });
  // PCL keeps the empty old roots of a box grown before any point as branches.
  for (const Phantom& ph : phantoms_) {
    const LeafId cube{ph.min, std::uint32_t(ph.level)};
    index->try_emplace(cube, 0);
    addNode(cube);
  }
  return index;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
std::size_t OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getBranchCount() const {
  return branchIndex()->size();
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::NodeIterator::NodeIterator(
    const OctreePointCloud* tree, bool depth_first, Stops stops, uindex_t max_depth)
    : tree_(tree),
      branches_(tree->branchIndex()),
      depth_first_(depth_first),
      stops_(stops),
      max_depth_(max_depth) {
  pending_.push_back(nodeAt(octree::OctreeKey(0, 0, 0), 0));
  at_end_ = false;
  advance();
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::Node
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::NodeIterator::nodeAt(const octree::OctreeKey& key,
                                                                                 uindex_t depth) const {
  const std::uint32_t level = tree_->depth_ - depth;
  const LeafId cube{tree_->pclKeyToTreeKey(octree::OctreeKey(key.x << level, key.y << level, key.z << level)),
                    level};
  const auto it = branches_->find(cube);
  return it != branches_->end() ? Node{key, depth, it->second, false} : Node{key, depth, 0, true};
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::NodeIterator::advance() {
  const uindex_t limit = std::min(max_depth_, tree_->depth_);
  while (!pending_.empty()) {
    if (depth_first_) {
      node_ = pending_.back();
      pending_.pop_back();
    } else {
      node_ = pending_.front();
      pending_.pop_front();
    }
    if (!node_.leaf && node_.depth < limit) {
      // Children in PCL's order: depth first pushes them last to first, so the first comes out first.
      for (unsigned i = 0; i < 8; ++i) {
        const unsigned c = depth_first_ ? 7 - i : i;
        if (!(node_.children >> c & 1u)) continue;
        const octree::OctreeKey& k = node_.key;
        pending_.push_back(
            nodeAt(octree::OctreeKey(k.x << 1 | (c >> 2 & 1u), k.y << 1 | (c >> 1 & 1u), k.z << 1 | (c & 1u)),
                   node_.depth + 1));
      }
    }
    if (stops_ == Stops::All || (stops_ == Stops::Leaves && node_.leaf) ||
        (stops_ == Stops::OneDepth && node_.depth == max_depth_))
      return;
  }
  at_end_ = true;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
typename OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::NodeIterator
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::fixed_depth_begin(
    uindex_t fixed_depth_arg) const {
  if (fixed_depth_arg > depth_) {
    PCL_WARN(
        "[pcl::fot::OctreePointCloud::fixed_depth_begin] Depth %u is deeper than the octree (depth %u).\n",
        fixed_depth_arg, depth_);
    return end();
  }
  return NodeIterator(this, false, NodeIterator::Stops::OneDepth, fixed_depth_arg);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::deleteTree() {
  min_[0] = min_[1] = min_[2] = max_[0] = max_[1] = max_[2] = 0;
  bounding_box_defined_ = false;
  tree_.clear();
  leaves_.clear();
  last_.leaf = nullptr;
  phantoms_.clear();
  ++version_;
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
  if (getLeafCount() != 0) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::defineBoundingBox] The octree must be empty to define its box.\n");
    return;
  }
  const double in[6] = {min_x_arg, min_y_arg, min_z_arg, max_x_arg, max_y_arg, max_z_arg};
  for (double v : in)
    if (!std::isfinite(v)) {
      PCL_ERROR("[pcl::fot::OctreePointCloud::defineBoundingBox] The box must be finite.\n");
      return;
    }
  const double saved_min[3] = {min_[0], min_[1], min_[2]}, saved_max[3] = {max_[0], max_[1], max_[2]};
  const uindex_t saved_depth = depth_;
  min_[0] = std::min(min_x_arg, max_x_arg);
  min_[1] = std::min(min_y_arg, max_y_arg);
  min_[2] = std::min(min_z_arg, max_z_arg);
  max_[0] = std::max(min_x_arg, max_x_arg);
  max_[1] = std::max(min_y_arg, max_y_arg);
  max_[2] = std::max(min_z_arg, max_z_arg);
  getKeyBitSize();
  if (depth_ > detail::kMaxPclDepth) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::defineBoundingBox] The box spans more than 2^%u cells per axis.\n",
        detail::kMaxPclDepth);
    std::copy(saved_min, saved_min + 3, min_);
    std::copy(saved_max, saved_max + 3, max_);
    depth_ = saved_depth;
    return;
  }
  offset_ = {0, 0, 0};
  phantoms_.clear();
  bounding_box_defined_ = true;
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
  min_x_arg = min_[0];
  min_y_arg = min_[1];
  min_z_arg = min_[2];
  max_x_arg = max_[0];
  max_y_arg = max_[1];
  max_z_arg = max_[2];
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
double OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getVoxelSquaredSideLen(
    uindex_t tree_depth_arg) const {
  const double side = std::ldexp(resolution_, int(depth_) - int(tree_depth_arg));
  return side * side;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getVoxelBounds(
    const NodeIterator& iterator, Eigen::Vector3f& min_pt, Eigen::Vector3f& max_pt) const {
  const octree::OctreeKey& key = iterator.getCurrentOctreeKey();
  const double side = std::ldexp(resolution_, int(depth_) - int(iterator.getCurrentOctreeDepth()));
  const uindex_t k[3] = {key.x, key.y, key.z};
  for (int a = 0; a < 3; ++a) {
    min_pt(a) = static_cast<float>(static_cast<double>(k[a]) * side + min_[a]);
    max_pt(a) = static_cast<float>(static_cast<double>(k[a] + 1) * side + min_[a]);
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t
OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getApproxIntersectedVoxelCentersBySegment(
    const Eigen::Vector3f& origin, const Eigen::Vector3f& end, AlignedPointTVector& voxel_center_list,
    float precision) {
  // PCL's walk in small float steps; keys are only taken inside the box, where PCL's are defined.
  const float step_size = static_cast<float>(resolution_) * precision;
  if (!(end - origin).allFinite() || !(step_size > 0.0f) || !std::isfinite(step_size)) {
    PCL_ERROR(
        "[pcl::fot::OctreePointCloud::getApproxIntersectedVoxelCentersBySegment] The segment must "
        "be finite and the precision positive.\n");
    return static_cast<uindex_t>(voxel_center_list.size());
  }
  Eigen::Vector3f direction = end - origin;
  const float norm = direction.norm();
  direction.normalize();
  const double nsteps = std::max(1.0, std::floor(double(norm / step_size)));
  octree::OctreeKey prev_key;
  bool have_prev = false;
  auto add = [&](const Eigen::Vector3f& p) {
    if (!isPointWithinBoundingBox(p.x(), p.y(), p.z())) return;
    const octree::OctreeKey key = pclKey(p.x(), p.y(), p.z());
    if (have_prev && key == prev_key) return;
    prev_key = key;
    have_prev = true;
    PointT center;
    pclKeyToCenter(key, center);
    voxel_center_list.push_back(center);
  };
  // Only the steps near the part of the segment inside the box can add a voxel: a far end costs nothing.
  double t_in = 0.0, t_out = norm;
  for (int a = 0; a < 3; ++a) {
    const double o = origin[a], d = direction[a];
    if (d == 0.0) {
      if (o < min_[a] || o >= max_[a]) t_in = t_out + 1.0;
      continue;
    }
    double t0 = (min_[a] - o) / d, t1 = (max_[a] - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  if (bounding_box_defined_ && t_in <= t_out) {
    // A margin for the float rounding of the samples, which grows with their coordinates.
    const double slack = 2.0 + (double(norm) + origin.cwiseAbs().sum()) * 1e-6 / step_size;
    const double first = std::max(0.0, std::floor(t_in / step_size - slack));
    const double last = std::min(nsteps, std::ceil(t_out / step_size + slack));
    if (last - first > 0x1p32 || last > 0x1p53) {
      PCL_ERROR(
          "[pcl::fot::OctreePointCloud::getApproxIntersectedVoxelCentersBySegment] Refused: %g steps "
          "at this precision.\n",
          last - first);
      return static_cast<uindex_t>(voxel_center_list.size());
    }
    for (auto i = std::uint64_t(first); i < std::uint64_t(last); ++i)
      add(origin + (direction * step_size * static_cast<float>(i)));
  }
  add(end);
  return static_cast<uindex_t>(voxel_center_list.size());
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
template <typename Visit>
void OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::walkRay(const Eigen::Vector3f& origin,
                                                                         const Eigen::Vector3f& direction,
                                                                         Visit&& visit) const {
  const double norm = direction.cast<double>().norm();
  if (!bounding_box_defined_ || !(norm > 0.0) || !std::isfinite(norm) || !origin.allFinite()) return;
  // Clip the ray to the box (slab test), then walk its cells from the entry on.
  double t_in = 0.0, t_out = std::numeric_limits<double>::infinity();
  double dir[3];
  for (int a = 0; a < 3; ++a) {
    dir[a] = double(direction[a]) / norm;
    if (dir[a] == 0.0) {
      if (origin[a] < min_[a] || origin[a] >= max_[a]) return;
      continue;
    }
    double t0 = (min_[a] - origin[a]) / dir[a], t1 = (max_[a] - origin[a]) / dir[a];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  if (t_in >= t_out) return;
  const std::int64_t cells = std::int64_t(1) << depth_;
  std::int32_t start[3];
  double rel[3];
  for (int a = 0; a < 3; ++a) {
    const double entry = origin[a] + t_in * dir[a];
    const double k = std::floor((entry - min_[a]) / resolution_);
    start[a] = std::int32_t(std::min<double>(std::max<double>(k, 0.0), double(cells - 1)));
    rel[a] = double(origin[a]) - min_[a];
  }
  const CellGrid box_grid(resolution_);  // PCL's frame: keys counted from the box's lower corner
  RayWalker walker(box_grid, Key{start[0], start[1], start[2]}, rel, dir);
  ConstAccessor cells_of(tree_);
  const NodeWord* words = tree_.words();
  for (std::int64_t budget = 3 * cells + 3; budget > 0;) {
    const Key k = walker.key();
    if (k.x < 0 || k.y < 0 || k.z < 0 || k.x >= cells || k.y >= cells || k.z >= cells) break;
    const octree::OctreeKey pk(uindex_t(k.x), uindex_t(k.y), uindex_t(k.z));
    const Key key = pclKeyToTreeKey(pk);
    const unsigned level = cells_of.locatePath(key);  // 0: outside the tree's root, where nothing is
    const TreeCoord c(key);
    const bool occupied =
        level > 0 && node::state(words[cells_of.pathOffset(level)], c.octant(level)) == CellState::Occupied;
    if (occupied && !visit(pk)) break;
    // An empty octant, 2^(level-1) cells per axis, is crossed without reading the tree again: the same
    // steps, so the same cells afterwards.
    const unsigned span = occupied || level == 0 ? 0 : level - 1;
    for (bool inside = true; inside && budget > 0; --budget) {
      walker.step();
      const Key w = walker.key();
      const TreeCoord n(Key{w.x + offset_[0], w.y + offset_[1], w.z + offset_[2]});
      inside = (((n[0] ^ c[0]) | (n[1] ^ c[1]) | (n[2] ^ c[2])) >> span) == 0;
    }
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t OctreePointCloud<PointT, LeafContainerT, BranchContainerT>::getIntersectedVoxelCenters(
    Eigen::Vector3f origin, Eigen::Vector3f direction, AlignedPointTVector& voxel_center_list,
    uindex_t max_voxel_count) const {
  voxel_center_list.clear();
  walkRay(origin, direction, [&](const octree::OctreeKey& key) {
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
  const LeafNode* previous = nullptr;  // a shallow leaf spans several cells in a row
  walkRay(origin, direction, [&](const octree::OctreeKey& key) {
    const LeafNode* leaf = findLeaf(key);
    if (!leaf || leaf == previous) return true;
    previous = leaf;
    leaf->getContainer().getPointIndices(k_indices);
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
