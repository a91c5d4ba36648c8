#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <pcl/common/point_tests.h>
#include <pcl/console/print.h>

#include <pcl_fot/detail/bits.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_search.h>
#include <pcl_fot/pcl/octree/impl/octree_point_cloud.hpp>

namespace pcl {
namespace fot {
namespace detail {

/**
 * A key's place in pcl::octree's depth-first order, where the child index at each level is x·4 + y·2 + z:
 * the key's bits interleaved, x above y above z.
 */
struct PclOrderCode {
  std::uint64_t high, low;  // bits 28..14 of each axis, then bits 13..0
  explicit PclOrderCode(const octree::OctreeKey& k)
      : high(morton3(k.z >> 14, k.y >> 14, k.x >> 14)),
        low(morton3(k.z & 0x3fff, k.y & 0x3fff, k.x & 0x3fff)) {}
  bool operator<(const PclOrderCode& o) const { return high < o.high || (high == o.high && low < o.low); }
};

/** pcl::octree's point distance, as it computes it (Eigen's squaredNorm sums x² + (y² + z²)). */
template <typename PointT>
float octreeSquaredDistance(const PointT& a, const PointT& b) {
  return (a.getVector3fMap() - b.getVector3fMap()).squaredNorm();
}

}  // namespace detail

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
std::shared_ptr<const PointIndex>
OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::pointIndex() const {
  return cache_.get(this->version(), [&] {
    Indices points;
    this->appendEveryLeafIndices(points);
    // Indices beyond the cloud (it was swapped for a smaller one) are left out, not read.
    const auto size = static_cast<index_t>(this->input_->size());
    points.erase(std::remove_if(points.begin(), points.end(), [&](index_t i) { return i < 0 || i >= size; }),
                 points.end());
    auto index = std::make_shared<PointIndex>();
    if (!this->input_->empty())
      index->build(&(*this->input_)[0].x, this->input_->size(), sizeof(PointT), points.data(), points.size());
    return index;
  });
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::addPointIdx(uindex_t point_idx_arg) {
  const std::uint64_t before = this->version();
  OctreeT::addPointIdx(point_idx_arg);
  if (this->version() == before) return;  // refused
  // An index added twice (PCL keeps both) makes PointIndex::add throw: the index is then built anew.
  const auto index = static_cast<std::int32_t>(point_idx_arg);
  cache_.follow(before, this->version(), [&](PointIndex& points) {
    points.add(&(*this->input_)[point_idx_arg].x, 1, sizeof(PointT), &index);
  });
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::removeLeaf(uindex_t idx_x_arg,
                                                                                  uindex_t idx_y_arg,
                                                                                  uindex_t idx_z_arg) {
  Indices gone;
  if (this->existLeaf(idx_x_arg, idx_y_arg, idx_z_arg))
    this->appendLeafIndices(this->findSlot(octree::OctreeKey(idx_x_arg, idx_y_arg, idx_z_arg)), gone);
  const std::uint64_t before = this->version();
  OctreeT::removeLeaf(idx_x_arg, idx_y_arg, idx_z_arg);
  cache_.follow(before, this->version(),
                [&](PointIndex& points) { points.remove(gone.data(), gone.size()); });
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
const PointT* OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::inputPoint(
    uindex_t index, const char* caller) const {
  if (!this->input_ || index >= this->input_->size()) {
    PCL_ERROR("[pcl::fot::OctreePointCloudSearch::%s] Index %zu is not in the input cloud.\n", caller,
              static_cast<std::size_t>(index));
    return nullptr;
  }
  return &(*this->input_)[index];
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
bool OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::canSearch(const PointT& p_q,
                                                                                 const char* caller) const {
  if (!isFinite(p_q)) {
    PCL_ERROR("[pcl::fot::OctreePointCloudSearch::%s] The query point is not finite.\n", caller);
    return false;
  }
  if (!this->input_ || this->getLeafCount() == 0) {
    PCL_ERROR("[pcl::fot::OctreePointCloudSearch::%s] The octree holds no points yet.\n", caller);
    return false;
  }
  return true;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
std::vector<typename OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::Slot>
OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::leavesAround(
    const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
  std::vector<Slot> leaves;
  if (this->getLeafCount() == 0 || !(lo.array() <= hi.array()).all()) return leaves;
  double box_lo[3], box_hi[3];
  this->getBoundingBox(box_lo[0], box_lo[1], box_lo[2], box_hi[0], box_hi[1], box_hi[2]);
  // A point keeps the voxel it was added to, whose key was computed in the box of that moment: after the
  // box grows, a key computed now may differ by one. One voxel more on each side finds them all.
  const double res = this->getResolution();
  const std::int64_t last = (std::int64_t(1) << this->getTreeDepth()) - 1;
  std::int64_t from[3], to[3];
  for (int a = 0; a < 3; ++a) {
    if (hi[a] < box_lo[a] - res || lo[a] > box_hi[a] + res) return leaves;
    from[a] = std::max<std::int64_t>(
        0, std::int64_t(std::floor((std::max(lo[a], box_lo[a] - res) - box_lo[a]) / res)) - 1);
    to[a] = std::min<std::int64_t>(
        last, std::int64_t(std::floor((std::min(hi[a], box_hi[a] + res) - box_lo[a]) / res)) + 1);
    if (from[a] > to[a]) return leaves;
  }
  const auto tree_key = [&](const std::int64_t k[3]) {
    return this->pclKeyToTreeKey(octree::OctreeKey(uindex_t(k[0]), uindex_t(k[1]), uindex_t(k[2])));
  };
  const Key first = tree_key(from), last_key = tree_key(to);
  const Key offset = this->pclKeyToTreeKey(octree::OctreeKey(0, 0, 0));
  std::vector<std::pair<detail::PclOrderCode, octree::OctreeKey>> found;
  this->getFastOctTree().forEachRegionInBox(first, last_key, [&](const Region& r) {
    if (r.state != CellState::Occupied) return true;
    const std::int32_t side = std::int32_t(1) << r.level;
    for (std::int32_t x = std::max(r.min_key.x, first.x); x <= std::min(r.min_key.x + side - 1, last_key.x);
         ++x)
      for (std::int32_t y = std::max(r.min_key.y, first.y); y <= std::min(r.min_key.y + side - 1, last_key.y);
           ++y)
        for (std::int32_t z = std::max(r.min_key.z, first.z);
             z <= std::min(r.min_key.z + side - 1, last_key.z); ++z) {
          const octree::OctreeKey key(uindex_t(x - offset.x), uindex_t(y - offset.y), uindex_t(z - offset.z));
          found.emplace_back(detail::PclOrderCode(key), key);
        }
    return true;
  });
  // A shallow leaf (dynamic depth) spans consecutive cells in this order: it is listed once.
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<octree::OctreeKey> keys(found.size());
  for (std::size_t i = 0; i < found.size(); ++i) keys[i] = found[i].second;
  std::vector<Slot> slots;
  this->findSlots(keys, slots);
  for (const Slot leaf : slots)
    if (leaf != OctreeT::kNoLeaf && (leaves.empty() || leaves.back() != leaf)) leaves.push_back(leaf);
  return leaves;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
bool OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::voxelSearch(
    const PointT& point, Indices& point_idx_data) const {
  const Slot leaf = this->slotAtPoint(point);
  if (leaf == OctreeT::kNoLeaf) return false;
  this->appendLeafIndices(leaf, point_idx_data);
  return true;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
bool OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::voxelSearch(
    uindex_t index, Indices& point_idx_data) const {
  const PointT* p = inputPoint(index, "voxelSearch");
  return p && voxelSearch(*p, point_idx_data);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::nearestKSearch(
    const PointT& p_q, uindex_t k, Indices& k_indices, std::vector<float>& k_sqr_distances) const {
  k_indices.clear();
  k_sqr_distances.clear();
  if (k == 0) {
    PCL_ERROR("[pcl::fot::OctreePointCloudSearch::nearestKSearch] k must be at least 1.\n");
    return 0;
  }
  if (!canSearch(p_q, "nearestKSearch")) return 0;
  const float q[3] = {p_q.x, p_q.y, p_q.z};
  return static_cast<uindex_t>(
      pointIndex()->nearestK(q, k, Metric::EuclideanEigen, k_indices, k_sqr_distances));
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::nearestKSearch(
    uindex_t index, uindex_t k, Indices& k_indices, std::vector<float>& k_sqr_distances) const {
  k_indices.clear();
  k_sqr_distances.clear();
  const PointT* p = inputPoint(index, "nearestKSearch");
  return p ? nearestKSearch(*p, k, k_indices, k_sqr_distances) : 0;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::approxNearestSearch(
    const PointT& p_q, index_t& result_index, float& sqr_distance) const {
  if (!canSearch(p_q, "approxNearestSearch")) return;
  const Slot leaf = this->approxSlot(p_q);
  if (leaf == OctreeT::kNoLeaf) return;
  Indices points;
  this->appendLeafIndices(leaf, points);
  float smallest = std::numeric_limits<float>::max();
  for (const index_t i : points) {
    const float d = detail::octreeSquaredDistance((*this->input_)[i], p_q);
    if (d >= smallest) continue;
    result_index = i;
    smallest = sqr_distance = d;
  }
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
void OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::approxNearestSearch(
    uindex_t query_index, index_t& result_index, float& sqr_distance) const {
  if (const PointT* p = inputPoint(query_index, "approxNearestSearch"))
    approxNearestSearch(*p, result_index, sqr_distance);
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::radiusSearch(
    const PointT& p_q, const double radius, Indices& k_indices, std::vector<float>& k_sqr_distances,
    uindex_t max_nn) const {
  k_indices.clear();
  k_sqr_distances.clear();
  if (!(radius >= 0)) {
    PCL_ERROR("[pcl::fot::OctreePointCloudSearch::radiusSearch] The radius must be 0 or more.\n");
    return 0;
  }
  if (!canSearch(p_q, "radiusSearch")) return 0;
  const Eigen::Vector3d q = p_q.getVector3fMap().template cast<double>();
  const Eigen::Vector3d reach = Eigen::Vector3d::Constant(radius);
  const double radius_squared = radius * radius;
  Indices points;
  for (const Slot leaf : leavesAround(q - reach, q + reach)) {
    points.clear();
    this->appendLeafIndices(leaf, points);
    for (const index_t i : points) {
      const float d = detail::octreeSquaredDistance((*this->input_)[i], p_q);
      if (d > radius_squared) continue;
      k_indices.push_back(i);
      k_sqr_distances.push_back(d);
      if (max_nn != 0 && k_indices.size() == max_nn) return max_nn;
    }
  }
  return static_cast<uindex_t>(k_indices.size());
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::radiusSearch(
    uindex_t index, const double radius, Indices& k_indices, std::vector<float>& k_sqr_distances,
    uindex_t max_nn) const {
  k_indices.clear();
  k_sqr_distances.clear();
  const PointT* p = inputPoint(index, "radiusSearch");
  return p ? radiusSearch(*p, radius, k_indices, k_sqr_distances, max_nn) : 0;
}

template <typename PointT, typename LeafContainerT, typename BranchContainerT>
uindex_t OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>::boxSearch(
    const Eigen::Vector3f& min_pt, const Eigen::Vector3f& max_pt, Indices& k_indices) const {
  k_indices.clear();
  if (!min_pt.allFinite() || !max_pt.allFinite()) {
    PCL_ERROR("[pcl::fot::OctreePointCloudSearch::boxSearch] The box must be finite.\n");
    return 0;
  }
  Indices points;
  for (const Slot leaf : leavesAround(min_pt.cast<double>(), max_pt.cast<double>())) {
    points.clear();
    this->appendLeafIndices(leaf, points);
    for (const index_t i : points) {
      const PointT& p = (*this->input_)[i];
      if (p.x >= min_pt(0) && p.x <= max_pt(0) && p.y >= min_pt(1) && p.y <= max_pt(1) && p.z >= min_pt(2) &&
          p.z <= max_pt(2))
        k_indices.push_back(i);
    }
  }
  return static_cast<uindex_t>(k_indices.size());
}

}  // namespace fot
}  // namespace pcl

#define PCL_INSTANTIATE_OctreePointCloudSearch(T) \
  template class PCL_EXPORTS pcl::fot::OctreePointCloudSearch<T>;
