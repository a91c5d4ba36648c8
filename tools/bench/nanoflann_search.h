#pragma once
// nanoflann behind PCL's KdTree interface, set up as PCL 1.15's pcl::search::KdTreeNanoflann sets it up (PCL
// 1.13 has none), so PCL's algorithms can take it through setSearchMethod and the benchmarks time what a PCL
// user of nanoflann pays: the pass that maps valid points, the tree over the cloud's own memory where every
// point is valid (a copy of the valid ones otherwise), and the indices mapped back after each query.

#include <algorithm>
#include <memory>
#include <vector>

#include <pcl/common/point_tests.h>
#include <pcl/search/kdtree.h>

#include "nanoflann_points.h"

namespace fot_bench {

/** A pcl::search::KdTree answered by a nanoflann tree (L2, float) with leaves of `leaf_size` points. */
template <typename PointT>
class NanoflannKdTree : public pcl::search::KdTree<PointT> {
 public:
  using Base = pcl::search::KdTree<PointT>;
  using Base::nearestKSearch;
  using Base::radiusSearch;
  using typename Base::PointCloudConstPtr;

  explicit NanoflannKdTree(std::size_t leaf_size) : Base(true), leaf_size_(leaf_size) {
    this->name_ = "NanoflannKdTree";
  }

  void setInputCloud(const PointCloudConstPtr& cloud,
                     const pcl::IndicesConstPtr& indices = pcl::IndicesConstPtr()) override {
    this->input_ = cloud;
    this->indices_ = indices;
    mapping_.clear();
    copy_.clear();
    const std::size_t n = indices ? indices->size() : cloud->size();
    mapping_.reserve(n);
    for (std::size_t j = 0; j < n; ++j) {
      const pcl::index_t i = indices ? (*indices)[j] : pcl::index_t(j);
      if (pcl::isFinite((*cloud)[std::size_t(i)])) mapping_.push_back(i);
    }
    identity_ = true;
    for (std::size_t j = 0; identity_ && j < mapping_.size(); ++j) identity_ = mapping_[j] == pcl::index_t(j);
    points_.count = mapping_.size();
    if (identity_ && !mapping_.empty()) {
      points_.xyz = &(*cloud)[0].x;
      points_.stride = sizeof(PointT) / sizeof(float);
    } else {
      copy_.reserve(3 * mapping_.size());
      for (const pcl::index_t i : mapping_) {
        const PointT& p = (*cloud)[std::size_t(i)];
        copy_.insert(copy_.end(), {p.x, p.y, p.z});
      }
      points_.xyz = copy_.data();
      points_.stride = 3;
    }
    tree_ = std::make_unique<Tree>(3, points_, nanoflann::KDTreeSingleIndexAdaptorParams(leaf_size_));
    tree_->buildIndex();
  }

  int nearestKSearch(const PointT& point, int k, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override {
    if (k <= 0 || mapping_.empty() || !pcl::isFinite(point)) {
      k_indices.clear();
      k_sqr_distances.clear();
      return 0;
    }
    const float q[3] = {point.x, point.y, point.z};
    return int(nearest(q, std::size_t(k), k_indices, k_sqr_distances));
  }

  int radiusSearch(const PointT& point, double radius, pcl::Indices& k_indices,
                   std::vector<float>& k_sqr_distances, unsigned int max_nn = 0) const override {
    k_indices.clear();
    k_sqr_distances.clear();
    if (!(radius > 0) || mapping_.empty() || !pcl::isFinite(point)) return 0;
    const float q[3] = {point.x, point.y, point.z};
    const float r = float(radius), bound = r * r;  // squared in float, as PCL 1.15 does
    if (max_nn > 0) {  // as PCL 1.15 with nanoflann before 1.5.1: the max_nn nearest, those beyond cut off
      std::size_t kept = nearest(q, max_nn, k_indices, k_sqr_distances);
      while (kept > 0 && k_sqr_distances[kept - 1] > bound) --kept;
      k_indices.resize(kept);
      k_sqr_distances.resize(kept);
      return int(kept);
    }
    // As PCL 1.15 with nanoflann before 1.6: the pairs found, sorted, then split into the two vectors.
    std::vector<std::pair<pcl::index_t, float>> matches;
    tree_->radiusSearch(q, bound, matches, nanoflann::SearchParams(32, 0.0f, true));
    k_indices.resize(matches.size());
    k_sqr_distances.resize(matches.size());
    for (std::size_t i = 0; i < matches.size(); ++i) {
      k_indices[i] = matches[i].first;
      k_sqr_distances[i] = matches[i].second;
    }
    mapBack(k_indices);
    return int(matches.size());
  }

 private:
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<
      nanoflann::L2_Simple_Adaptor<float, StridedPoints, float, pcl::index_t>, StridedPoints, 3,
      pcl::index_t>;
  /** The min(k, size) nearest, as PCL 1.15's k-NN: into the caller's vectors, indices mapped back. */
  std::size_t nearest(const float q[3], std::size_t k, pcl::Indices& indices,
                      std::vector<float>& distances) const {
    const std::size_t n = std::min(k, mapping_.size());
    indices.resize(n);
    distances.resize(n);
    nanoflann::KNNResultSet<float, pcl::index_t> result(n);
    result.init(indices.data(), distances.data());
    tree_->findNeighbors(result, q, nanoflann::SearchParams());
    mapBack(indices);
    return n;
  }
  void mapBack(pcl::Indices& indices) const {
    if (!identity_)
      for (pcl::index_t& i : indices) i = mapping_[std::size_t(i)];
  }

  std::size_t leaf_size_;
  pcl::Indices mapping_;  // the tree's point i is the cloud's point mapping_[i]
  bool identity_ = true;
  std::vector<float> copy_;
  StridedPoints points_;
  std::unique_ptr<Tree> tree_;
};

}  // namespace fot_bench
