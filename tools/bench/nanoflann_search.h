#pragma once
// nanoflann behind PCL's KdTree interface, as PCL 1.15's pcl::search::KdTreeNanoflann puts it there (PCL
// 1.13 has none): so PCL's algorithms can take it through setSearchMethod in the benchmarks.

#include <cmath>
#include <memory>
#include <vector>

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
    points_.xyz.clear();
    ids_.clear();
    const std::size_t n = indices ? indices->size() : cloud->size();
    for (std::size_t j = 0; j < n; ++j) {
      const pcl::index_t i = indices ? (*indices)[j] : pcl::index_t(j);
      const PointT& p = (*cloud)[std::size_t(i)];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
      points_.xyz.insert(points_.xyz.end(), {p.x, p.y, p.z});
      ids_.push_back(i);
    }
    tree_ = std::make_unique<Tree>(3, points_, nanoflann::KDTreeSingleIndexAdaptorParams(leaf_size_));
    tree_->buildIndex();
  }

  int nearestKSearch(const PointT& point, int k, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override {
    k_indices.clear();
    k_sqr_distances.clear();
    if (k <= 0 || ids_.empty() || !finite(point)) return 0;
    const float q[3] = {point.x, point.y, point.z};
    std::vector<unsigned> at(static_cast<std::size_t>(k));
    k_sqr_distances.resize(std::size_t(k));
    const std::size_t found = tree_->knnSearch(q, std::size_t(k), at.data(), k_sqr_distances.data());
    k_sqr_distances.resize(found);
    for (std::size_t i = 0; i < found; ++i) k_indices.push_back(ids_[at[i]]);
    return int(found);
  }

  int radiusSearch(const PointT& point, double radius, pcl::Indices& k_indices,
                   std::vector<float>& k_sqr_distances, unsigned int max_nn = 0) const override {
    k_indices.clear();
    k_sqr_distances.clear();
    if (!(radius > 0) || ids_.empty() || !finite(point)) return 0;
    const float q[3] = {point.x, point.y, point.z};
    std::vector<std::pair<unsigned, float>> matches;
    tree_->radiusSearch(q, float(radius * radius), matches, nanoflann::SearchParams(32, 0.0f, true));
    if (max_nn > 0 && matches.size() > max_nn) matches.resize(max_nn);
    for (const auto& m : matches) {
      k_indices.push_back(ids_[m.first]);
      k_sqr_distances.push_back(m.second);
    }
    return int(matches.size());
  }

 private:
  using Tree = NanoTree<nanoflann::L2_Simple_Adaptor<float, Points>>;
  static bool finite(const PointT& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  }

  std::size_t leaf_size_;
  Points points_;
  std::vector<pcl::index_t> ids_;
  std::unique_ptr<Tree> tree_;
};

}  // namespace fot_bench
