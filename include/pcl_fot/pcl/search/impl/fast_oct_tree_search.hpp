#pragma once

#include <algorithm>
#include <limits>

#include <pcl/console/print.h>

#include <pcl_fot/detail/cloud_fingerprint.h>
#include <pcl_fot/detail/worker_threads.h>
#include <pcl_fot/pcl/search/fast_oct_tree_search.h>

namespace pcl {
namespace fot {
namespace search {

template <typename PointT>
FastOctTreeSearch<PointT>::FastOctTreeSearch(bool sorted) : Base(sorted) {
  this->name_ = "FastOctTreeSearch";
}

template <typename PointT>
FastOctTreeSearch<PointT>::FastOctTreeSearch(double resolution, bool sorted)
    : Base(sorted), index_(resolution) {
  this->name_ = "FastOctTreeSearch";
}

template <typename PointT>
typename FastOctTreeSearch<PointT>::Source FastOctTreeSearch<PointT>::describe(
    const PointCloudConstPtr& cloud, const IndicesConstPtr& indices) const {
  Source s{cloud.get(), indices.get(), cloud ? cloud->size() : 0, 0};
  if (cloud && !cloud->empty())
    s.fingerprint =
        detail::cloudFingerprint(&(*cloud)[0].x, cloud->size(), sizeof(PointT),
                                 indices ? indices->data() : nullptr, indices ? indices->size() : 0);
  return s;
}

template <typename PointT>
#if PCL_VERSION_COMPARE(>=, 1, 14, 0)
bool
#else
void
#endif
FastOctTreeSearch<PointT>::setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices) {
  this->input_ = cloud;
  this->indices_ = indices;
  const Source source = describe(cloud, indices);
  if (!(source == built_)) {
    if (!cloud || cloud->empty()) {
      if (!cloud) PCL_ERROR("[pcl::fot::search::FastOctTreeSearch::setInputCloud] No input cloud.\n");
      index_.build(nullptr, 0, sizeof(PointT));
    } else if (indices) {
      index_.build(&(*cloud)[0].x, cloud->size(), sizeof(PointT), indices->data(), indices->size());
    } else {
      index_.build(&(*cloud)[0].x, cloud->size(), sizeof(PointT));
    }
    built_ = source;
    skipped_ = (indices ? indices->size() : (cloud ? cloud->size() : 0)) - index_.size();
  }
  grown_.reset();
#if PCL_VERSION_COMPARE(>=, 1, 14, 0)
  return cloud != nullptr;
#endif
}

template <typename PointT>
std::size_t FastOctTreeSearch<PointT>::addPoints(const PointCloud& cloud) {
  if (!grown_) {
    grown_ = this->input_ ? make_shared<PointCloud>(*this->input_) : make_shared<PointCloud>();
    this->input_ = grown_;
    built_ = Source{};
  }
  const std::size_t first = grown_->size();
  if (cloud.empty()) return 0;
  if (first + cloud.size() > std::size_t(std::numeric_limits<index_t>::max())) {
    PCL_ERROR(
        "[pcl::fot::search::FastOctTreeSearch::addPoints] %zu points would pass the largest index; "
        "none added.\n",
        cloud.size());
    return 0;
  }
  grown_->insert(grown_->end(), cloud.begin(), cloud.end());
  const std::size_t added = index_.add(&cloud[0].x, cloud.size(), sizeof(PointT), index_t(first));
  skipped_ += cloud.size() - added;
  return added;
}

template <typename PointT>
std::size_t FastOctTreeSearch<PointT>::removePoints(const Indices& indices) {
  const std::size_t n = this->input_ ? this->input_->size() : 0;
  for (const index_t i : indices)
    if (i < 0 || std::size_t(i) >= n) {
      PCL_ERROR(
          "[pcl::fot::search::FastOctTreeSearch::removePoints] Index %d lies outside the input cloud "
          "(%zu points); nothing removed.\n",
          int(i), n);
      return 0;
    }
  built_ = Source{};
  return index_.remove(indices.data(), indices.size());
}

template <typename PointT>
std::size_t FastOctTreeSearch<PointT>::removeBox(const Eigen::Vector3f& min_pt, const Eigen::Vector3f& max_pt,
                                                 bool inside, const char* caller) {
  if (!min_pt.allFinite() || !max_pt.allFinite() || (min_pt.array() > max_pt.array()).any()) {
    PCL_ERROR(
        "[pcl::fot::search::FastOctTreeSearch::%s] The box needs finite bounds, min <= max; nothing "
        "removed.\n",
        caller);
    return 0;
  }
  built_ = Source{};
  return index_.removeBox(min_pt.data(), max_pt.data(), inside);
}

template <typename PointT>
std::size_t FastOctTreeSearch<PointT>::removePoints(const Eigen::Vector3f& min_pt,
                                                    const Eigen::Vector3f& max_pt) {
  return removeBox(min_pt, max_pt, true, "removePoints");
}

template <typename PointT>
std::size_t FastOctTreeSearch<PointT>::removeOutsideBox(const Eigen::Vector3f& min_pt,
                                                        const Eigen::Vector3f& max_pt) {
  return removeBox(min_pt, max_pt, false, "removeOutsideBox");
}

template <typename PointT>
int FastOctTreeSearch<PointT>::nearestKSearch(const PointT& point, int k, Indices& k_indices,
                                              std::vector<float>& k_sqr_distances) const {
  const float q[3] = {point.x, point.y, point.z};
  if (k <= 0) {
    PCL_ERROR("[pcl::fot::search::FastOctTreeSearch::nearestKSearch] k = %d: it must be at least 1.\n", k);
    k_indices.clear();
    k_sqr_distances.clear();
    return 0;
  }
  const int found = int(index_.nearestK(q, std::size_t(k), metric_, k_indices, k_sqr_distances));
  if (found == 0 && index_.size() != 0) {
    // Only a query that is not finite finds nothing. PCL's correspondence estimation and fitness score read
    // the first result without the count: one at an infinite distance makes them pass over the point.
    k_indices.assign(1, index_.anyPoint());
    k_sqr_distances.assign(1, std::numeric_limits<float>::infinity());
  }
  return found;
}

template <typename PointT>
int FastOctTreeSearch<PointT>::radiusSearch(const PointT& point, double radius, Indices& k_indices,
                                            std::vector<float>& k_sqr_distances, unsigned int max_nn) const {
  if (!(radius > 0.0)) {  // as in BruteForce; KdTreeFLANN agrees at 0 and squares a negative radius
    if (!(radius == 0.0))
      PCL_ERROR("[pcl::fot::search::FastOctTreeSearch::radiusSearch] Radius %g: it must be 0 or more.\n",
                radius);
    k_indices.clear();
    k_sqr_distances.clear();
    return 0;
  }
  const float q[3] = {point.x, point.y, point.z};
  return int(index_.radiusSearch(q, radius, metric_, k_indices, k_sqr_distances, max_nn));
}

template <typename PointT>
template <typename Query>
void FastOctTreeSearch<PointT>::forEachQuery(std::size_t n, Query&& query) const {
  const std::size_t workers = detail::workerCount(threads_, n);
  // Contiguous runs keep each thread's queries together in space, as its LineBurst path likes them.
  detail::runWorkers(workers, [&](std::size_t w) {
    for (std::size_t i = n * w / workers, end = n * (w + 1) / workers; i < end; ++i) query(i);
  });
}

template <typename PointT>
void FastOctTreeSearch<PointT>::nearestKSearch(const PointCloud& cloud, const Indices& indices, int k,
                                               std::vector<Indices>& k_indices,
                                               std::vector<std::vector<float>>& k_sqr_distances) const {
  const std::size_t n = indices.empty() ? cloud.size() : indices.size();
  k_indices.resize(n);
  k_sqr_distances.resize(n);
  forEachQuery(n, [&](std::size_t i) {
    nearestKSearch(cloud[indices.empty() ? i : std::size_t(indices[i])], k, k_indices[i], k_sqr_distances[i]);
  });
}

template <typename PointT>
void FastOctTreeSearch<PointT>::radiusSearch(const PointCloud& cloud, const Indices& indices, double radius,
                                             std::vector<Indices>& k_indices,
                                             std::vector<std::vector<float>>& k_sqr_distances,
                                             unsigned int max_nn) const {
  const std::size_t n = indices.empty() ? cloud.size() : indices.size();
  k_indices.resize(n);
  k_sqr_distances.resize(n);
  forEachQuery(n, [&](std::size_t i) {
    radiusSearch(cloud[indices.empty() ? i : std::size_t(indices[i])], radius, k_indices[i],
                 k_sqr_distances[i], max_nn);
  });
}

}  // namespace search
}  // namespace fot
}  // namespace pcl

#define PCL_INSTANTIATE_FastOctTreeSearch(T) \
  template class PCL_EXPORTS pcl::fot::search::FastOctTreeSearch<T>;
