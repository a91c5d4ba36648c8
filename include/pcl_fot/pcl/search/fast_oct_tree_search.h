#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <pcl/pcl_base.h>
#include <pcl/pcl_config.h>
#include <pcl/search/kdtree.h>

#include <pcl_fot/search/point_index.h>

namespace pcl {
namespace fot {
namespace search {

/**
 * A pcl::search::KdTree that searches a FastOctTree instead of FLANN: ICP, CorrespondenceEstimation,
 * NormalEstimation, EuclideanClusterExtraction and the other PCL algorithms that take a KdTree or a Search
 * accept it as is (setSearchMethodTarget, setSearchMethod).
 *
 * It keeps PCL's search contract: indices refer to the input cloud even when an index subset is set;
 * Euclidean distances are squared floats, exactly those FLANN and BruteForce compute; k-NN results come
 * nearest first, and k = 1 always answers on a non-empty cloud; radius searches are inclusive, find nothing
 * for a radius of 0 (as KdTreeFLANN and BruteForce) or less (as BruteForce), and with max_nn > 0 keep the
 * nearest max_nn. Results are always nearest first, whatever setSortedResults says; ties go to the smaller
 * index. setMetric(Metric::Manhattan) makes every distance and radius Manhattan (L1). A query that is not
 * finite gets no results (0). k-NN then leaves one placeholder in the vectors, an indexed point at an
 * infinite distance: PCL's correspondence estimation and fitness score read the first result without the
 * count, and pass over such a point. So ICP ignores the NaN points of an organised source.
 *
 * setInputCloud builds the index (the tree plus a table from cells to points). Calling it again with the
 * same cloud, indices and coordinates, as ICP does twice per align(), costs one pass over the points.
 * Only x, y, z are used; a custom point representation is ignored.
 *
 * The index also updates in place, for maps that grow and forget (odometry, a sliding window, ICP against
 * a growing map): addPoints, removePoints and removeOutsideBox. Indices are places in getInputCloud(), a
 * cloud the search keeps from the first addPoints on (a copy of the input; the caller's cloud is never
 * written). A point keeps its index while it is held. A removed point is no longer found, and its index is
 * free: a point added later may get it (the lowest free index first), else the cloud grows by one. So the
 * cloud, and the index, take memory for the most points held at once, not for every point ever added, and
 * INT32_MAX bounds the points held, not those added. addPoints tells the caller the index of each point.
 *
 * getInputCloud() returns a snapshot: no later update changes the cloud it points to. An update writes to
 * the search's own cloud in place while no one else holds it, and to a copy of it otherwise (one copy of the
 * cloud at that update). Indices in results refer to the cloud getInputCloud() returns after the update,
 * so give PCL algorithms that keep a cloud (ICP's target) the new one after each update.
 *
 * Results after any updates equal those of a new search of the points held. No query may run during an
 * update: queries are const and may run from many threads at once, updates are not; a snapshot may be read
 * from any thread during an update. setInputCloud starts over from the cloud it is given.
 */
template <typename PointT>
class FastOctTreeSearch : public pcl::search::KdTree<PointT> {
 public:
  using Base = pcl::search::KdTree<PointT>;
  using Ptr = shared_ptr<FastOctTreeSearch<PointT>>;
  using ConstPtr = shared_ptr<const FastOctTreeSearch<PointT>>;
  using Base::nearestKSearch;
  using Base::radiusSearch;
  using typename Base::PointCloud;
  using typename Base::PointCloudConstPtr;

  /**
   * As pcl::search::KdTree(sorted): the cell edge is picked from each cloud given, at which its occupied
   * cells hold about 8 points or more on average (see PointIndex()).
   */
  explicit FastOctTreeSearch(bool sorted = true);
  /** A fixed cell edge in metres: one that puts 8 to 30 points in a cell on average searches fastest. */
  explicit FastOctTreeSearch(double resolution, bool sorted = true);

#if PCL_VERSION_COMPARE(>=, 1, 14, 0)
  bool
#else
  void
#endif
  setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices = IndicesConstPtr()) override;

  int nearestKSearch(const PointT& point, int k, Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override;
  int radiusSearch(const PointT& point, double radius, Indices& k_indices,
                   std::vector<float>& k_sqr_distances, unsigned int max_nn = 0) const override;

  /**
   * Adds the points of `cloud`, each at an index into getInputCloud(): the lowest index a removed point
   * left free, else one past the cloud's end; a batch's indices increase with its points. Those that are
   * not finite are skipped (counted by getSkippedCount) and take no index. Returns how many were added.
   * `cloud` may be getInputCloud() itself. If the points held would pass INT32_MAX, it is an error
   * (PCL_ERROR) and none are added.
   */
  std::size_t addPoints(const PointCloud& cloud);
  /**
   * As addPoints(cloud); indices[i] is then the index point i got, or pcl::UNAVAILABLE (-1) if it was
   * skipped. Pass them to removePoints to remove the batch.
   */
  std::size_t addPoints(const PointCloud& cloud, Indices& indices);
  /**
   * Removes the points with these indices; returns how many were held. Their indices may be given to points
   * added later. pcl::UNAVAILABLE (-1) is passed over; any other index outside the input cloud is an error
   * (PCL_ERROR): then nothing is removed.
   */
  std::size_t removePoints(const Indices& indices);
  /** Removes the points inside the box [min_pt, max_pt], bounds included; returns how many. */
  std::size_t removePoints(const Eigen::Vector3f& min_pt, const Eigen::Vector3f& max_pt);
  /** Removes the points outside the box [min_pt, max_pt]; returns how many. */
  std::size_t removeOutsideBox(const Eigen::Vector3f& min_pt, const Eigen::Vector3f& max_pt);
  /** Points held: those indexed, less those removed. */
  std::size_t size() const {
    return index_.size();
  }
  /** Points given since setInputCloud (by it or addPoints) that were not indexed: not finite. */
  std::size_t getSkippedCount() const {
    return skipped_;
  }

  /** PCL's batch searches, over setNumberOfThreads() threads; the results do not depend on the count. */
  void nearestKSearch(const PointCloud& cloud, const Indices& indices, int k, std::vector<Indices>& k_indices,
                      std::vector<std::vector<float>>& k_sqr_distances) const override;
  void radiusSearch(const PointCloud& cloud, const Indices& indices, double radius,
                    std::vector<Indices>& k_indices, std::vector<std::vector<float>>& k_sqr_distances,
                    unsigned int max_nn = 0) const override;

  /**
   * Threads for the batch searches: 1 (the default) runs them in the caller's thread, 0 takes every hardware
   * thread, and at most four per hardware thread are used. Single queries are safe from many threads at
   * once in any case.
   */
  void setNumberOfThreads(unsigned threads) {
    threads_ = threads;
  }
  unsigned getNumberOfThreads() const {
    return threads_;
  }

  void setMetric(Metric metric) {
    metric_ = metric;
  }
  Metric getMetric() const {
    return metric_;
  }
  /** The cell edge: the one given, or the one picked for the last cloud (0.01 m before the first). */
  double getResolution() const {
    return index_.resolution();
  }
  const PointIndex& getPointIndex() const {
    return index_;
  }

  PCL_MAKE_ALIGNED_OPERATOR_NEW

 private:
  /** Identifies what the index was built from: a repeated setInputCloud with the same input is free. */
  struct Source {
    const void* cloud = nullptr;
    const void* indices = nullptr;
    std::size_t size = 0;
    std::uint64_t fingerprint = 0;
    bool operator==(const Source& o) const {
      return cloud == o.cloud && indices == o.indices && size == o.size && fingerprint == o.fingerprint;
    }
  };
  Source describe(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices) const;
  /** A box's removal (inside or outside), after its check. */
  std::size_t removeBox(const Eigen::Vector3f& min_pt, const Eigen::Vector3f& max_pt, bool inside,
                        const char* caller);
  /**
   * At the first update since setInputCloud: the free indices are those of the input's points the index
   * does not hold (not finite, or not among its indices).
   */
  void trackFreeIndices();
  /** The indices of removed points become free. */
  void freeIndices(const std::vector<std::int32_t>& removed);
  /**
   * The cloud an update writes: the search's own, a copy of the input made at the first update, and copied
   * again whenever someone else holds it (a snapshot from getInputCloud()), which then stays as it was.
   */
  PointCloud& writableCloud();
  /** Runs query(i) for i in [0, n), split into contiguous runs over the threads. */
  template <typename Query>
  void forEachQuery(std::size_t n, Query&& query) const;

  PointIndex index_;
  Metric metric_ = Metric::Euclidean;
  Source built_;
  shared_ptr<PointCloud> grown_;  // the search's own cloud, input_ too, from the first addPoints on
  std::vector<index_t> free_;     // indices no point holds, below the cloud's size: a min-heap
  bool tracking_ = false;         // free_ is known: an update has run since setInputCloud
  std::size_t skipped_ = 0;
  unsigned threads_ = 1;
};

}  // namespace search
}  // namespace fot
}  // namespace pcl

#ifdef PCL_NO_PRECOMPILE
#include <pcl_fot/pcl/search/impl/fast_oct_tree_search.hpp>
#endif
