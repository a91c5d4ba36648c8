#pragma once

#include <algorithm>
#include <functional>
#include <limits>

#include <pcl/common/point_tests.h>
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
  std::vector<index_t>().swap(free_);
  tracking_ = false;
#if PCL_VERSION_COMPARE(>=, 1, 14, 0)
  return cloud != nullptr;
#endif
}

template <typename PointT>
void FastOctTreeSearch<PointT>::trackFreeIndices() {
  if (tracking_) return;
  tracking_ = true;
  free_.clear();
  if (!this->input_) return;
  const PointCloud& input = *this->input_;
  std::vector<bool> listed(input.size(), !this->indices_);
  if (this->indices_)
    for (const index_t i : *this->indices_)
      if (i >= 0 && std::size_t(i) < input.size()) listed[std::size_t(i)] = true;
  for (std::size_t i = 0; i < input.size(); ++i)
    if (!listed[i] || !pcl::isFinite(input[i])) free_.push_back(index_t(i));
  // Increasing: a min-heap as it is.
}

template <typename PointT>
void FastOctTreeSearch<PointT>::freeIndices(const std::vector<std::int32_t>& removed) {
  const auto lowest_first = std::greater<index_t>();
  if (removed.size() > free_.size() / 8) {
    free_.insert(free_.end(), removed.begin(), removed.end());
    std::make_heap(free_.begin(), free_.end(), lowest_first);
  } else {
    for (const std::int32_t i : removed) {
      free_.push_back(index_t(i));
      std::push_heap(free_.begin(), free_.end(), lowest_first);
    }
  }
}

template <typename PointT>
typename FastOctTreeSearch<PointT>::PointCloud& FastOctTreeSearch<PointT>::writableCloud() {
  if (!grown_ || this->input_ != grown_) {
    // The first addPoints since setInputCloud: the input is the caller's, and never written.
    grown_ = this->input_ ? make_shared<PointCloud>(*this->input_) : make_shared<PointCloud>();
    this->input_ = grown_;
  } else if (grown_.use_count() > 2) {
    // grown_ and input_ are the search's own references: any other is a snapshot, and keeps its cloud.
    grown_ = make_shared<PointCloud>(*grown_);
    this->input_ = grown_;
  }
  return *grown_;
}

template <typename PointT>
std::size_t FastOctTreeSearch<PointT>::addPoints(const PointCloud& cloud) {
  Indices indices;
  return addPoints(cloud, indices);
}

template <typename PointT>
std::size_t FastOctTreeSearch<PointT>::addPoints(const PointCloud& cloud, Indices& indices) {
  trackFreeIndices();
  std::size_t finite = 0;
  for (const PointT& p : cloud) finite += pcl::isFinite(p);
  const std::size_t slots = this->input_ ? this->input_->size() : 0;
  const std::size_t appended = finite > free_.size() ? finite - free_.size() : 0;
  if (slots + appended > std::size_t(std::numeric_limits<index_t>::max())) {
    PCL_ERROR(
        "[pcl::fot::search::FastOctTreeSearch::addPoints] %zu points would pass the largest index, with "
        "%zu held; none added.\n",
        finite, index_.size());
    indices.assign(cloud.size(), UNAVAILABLE);
    return 0;
  }
  indices.resize(cloud.size());
  if (cloud.empty()) {
    if (!this->input_) writableCloud();  // the search's cloud, empty, as after any addPoints
    return 0;
  }
  // addPoints(*getInputCloud()): the points are read from that cloud as it was. Holding it here keeps it
  // alive, and sends the writes to a copy (as for any snapshot).
  shared_ptr<const PointCloud> argument;
  if (this->input_ && &cloud == this->input_.get()) argument = this->input_;
  PointCloud& own = writableCloud();
  // Free indices first, lowest first, then the cloud's end: a batch's indices increase.
  const auto lowest_first = std::greater<index_t>();
  index_t end = index_t(own.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!pcl::isFinite(cloud[i])) {
      indices[i] = UNAVAILABLE;
    } else if (!free_.empty()) {
      std::pop_heap(free_.begin(), free_.end(), lowest_first);
      indices[i] = free_.back();
      free_.pop_back();
    } else {
      indices[i] = end++;
    }
  }
  if (std::size_t(end) > own.size()) own.resize(std::size_t(end));
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (indices[i] != UNAVAILABLE) own[std::size_t(indices[i])] = cloud[i];
  built_ = Source{};
  const std::size_t added = index_.add(&cloud[0].x, cloud.size(), sizeof(PointT), indices.data());
  skipped_ += cloud.size() - added;
  return added;
}

template <typename PointT>
std::size_t FastOctTreeSearch<PointT>::removePoints(const Indices& indices) {
  const std::size_t n = this->input_ ? this->input_->size() : 0;
  for (const index_t i : indices)
    if (i != UNAVAILABLE && (i < 0 || std::size_t(i) >= n)) {
      PCL_ERROR(
          "[pcl::fot::search::FastOctTreeSearch::removePoints] Index %d lies outside the input cloud "
          "(%zu points); nothing removed.\n",
          int(i), n);
      return 0;
    }
  trackFreeIndices();
  built_ = Source{};
  std::vector<std::int32_t> removed;
  const std::size_t count = index_.remove(indices.data(), indices.size(), &removed);
  freeIndices(removed);
  return count;
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
  trackFreeIndices();
  built_ = Source{};
  std::vector<std::int32_t> removed;
  const std::size_t count = index_.removeBox(min_pt.data(), max_pt.data(), inside, &removed);
  freeIndices(removed);
  return count;
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
