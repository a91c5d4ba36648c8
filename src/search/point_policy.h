#pragma once
// PointIndex's query policy: the distances from one query point to the points of the cells the tree walk
// (NeighbourWalk) visits, in either of its storages. Included by point_index.cpp only.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#include <pcl_fot/search/cell_buckets.h>
#include <pcl_fot/search/ranked_table.h>

#include "search/neighbour_walk.h"

namespace pcl {
namespace fot {
namespace detail {

/** A point found: its distance, index and place in the table (or its bucket). */
struct PointHit {
  float distance;
  std::int32_t index;
  std::uint32_t slot;  // where the point sits in the table
  bool operator<(const PointHit& o) const {
    return distance < o.distance || (distance == o.distance && index < o.index);
  }
};

/**
 * PCL's distances, to the bit: FLANN's L2_Simple and L1 sum the axes left to right in float; pcl::octree's
 * Eigen squaredNorm() sums x² + (y² + z²).
 */
inline float pointDistance(Metric metric, const float* p, const float q[3]) {
  const float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
  switch (metric) {
    case Metric::Euclidean:
      return dx * dx + dy * dy + dz * dz;
    case Metric::EuclideanEigen:
      return dx * dx + (dy * dy + dz * dz);
    default:
      return std::fabs(dx) + std::fabs(dy) + std::fabs(dz);
  }
}

inline constexpr float kOrigin[3] = {0.0f, 0.0f, 0.0f};

/**
 * The least distance PCL could report for a point in the box [lo, hi] from q: the gaps, squared and summed
 * in the order of pointDistance, whose float steps are each monotone, so no point in the box comes out below
 * it.
 */
inline float boxDistance(Metric metric, const float* lo, const float* hi, const float q[3]) {
  float gap[3];
  for (int a = 0; a < 3; ++a) gap[a] = std::max({lo[a] - q[a], q[a] - hi[a], 0.0f});
  if (metric == Metric::Manhattan) return gap[0] + gap[1] + gap[2];
  return pointDistance(metric, gap, kOrigin);
}

/** k for every point within the bound. */
constexpr std::size_t kAllPoints = std::numeric_limits<std::size_t>::max();
/**
 * Beyond this k, insertion in order, O(k) a point, costs more than a heap's O(log k) and a sort at the end:
 * callgrind put the crossover at k = 70 to 80 on a Kinect frame and a room scan.
 */
constexpr std::size_t kLargeK = 80;

/**
 * Distances from one query point, in metres, to the points of the cells the walk visits, as NeighbourWalk's
 * Policy. Storage is RankedTable (cells found by rank) or CellBuckets (cells found by key).
 */
template <typename Storage>
class PointPolicy {
  static constexpr bool kBuckets = std::is_same_v<Storage, CellBuckets>;

 public:
  using Distance = double;

  /** `qc`: the query in cells of edge `resolution` from the grid origin, where boxes are measured; one
   * scale turns them into metres. */
  PointPolicy(const Storage& storage, double resolution, const float q[3], const double qc[3], Metric metric,
              std::size_t k, double limit, std::vector<PointHit>& results)
      : storage_(storage),
        q_{q[0], q[1], q[2]},
        metric_(metric),
        k_(k),
        limit_(limit),
        bound_(limit),
        results_(results) {
    scale_ = metric != Metric::Manhattan ? resolution * resolution : resolution;
    const double slack =
        0x1p-48 * std::max({std::abs(qc[0]), std::abs(qc[1]), std::abs(qc[2])}) + 1e-22 / resolution;
    for (int a = 0; a < 3; ++a) low_[a] = qc[a] - slack, high_[a] = qc[a] + slack;
  }

  // Bounds are shaded down a little. Gaps in cells are measured from the query widened by a few ulps of its
  // cell coordinates, as much as its cell and a point's may be off by in rounding (a point exactly at the
  // query may lie in the next cell), and by 1e-22 m, below which float squares lose their precision among
  // denormals. Then a float distance may come out up to a few ulps below the exact one.
  void childGaps(const TreeCoord& lo, unsigned child_level, Distance gap[3][2]) const {
    const double half = double(std::uint64_t(1) << child_level);
    for (int a = 0; a < 3; ++a) {
      const double low = double(tree_coord::toKey(lo[a])), mid = low + half, high = mid + half;
      const double below = std::max({low - high_[a], low_[a] - mid, 0.0}),
                   above = std::max({mid - high_[a], low_[a] - high, 0.0});
      gap[a][0] = shade((metric_ != Metric::Manhattan ? below * below : below) * scale_);
      gap[a][1] = shade((metric_ != Metric::Manhattan ? above * above : above) * scale_);
    }
  }

  Distance exterior(const TreeCoord& lo, unsigned level) const {
    const double side = double(std::uint64_t(1) << level);
    double nearest = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      const double box_lo = double(tree_coord::toKey(lo[a]));
      nearest = std::min({nearest, low_[a] - box_lo, box_lo + side - high_[a]});
    }
    nearest = std::max(nearest, 0.0);
    return shade((metric_ != Metric::Manhattan ? nearest * nearest : nearest) * scale_);
  }

  bool worthVisiting(Distance lower_bound) const { return lower_bound <= bound_; }
  /** A table's box of a node's points bounds them tighter than the node's cube: far queries prune more. */
  bool mayImprove(Distance, const TreeCoord&, unsigned, std::size_t word) const {
    if constexpr (kBuckets) {
      return true;
    } else {
      if (word == kNoWord) return true;
      const float* box = storage_.wordBox(word).data();
      return !(double(pcl::fot::detail::boxDistance(metric_, box, box + 3, q_)) > bound_);
    }
  }
  bool settled(const TreeCoord& lo, unsigned level) const { return bound_ < exterior(lo, level); }
  bool wholeRegions() const { return false; }
  void visitRegion(const TreeCoord&, unsigned, std::uint64_t) {}

  /**
   * A cell's points, or in a table the outliers' (the run after the last cell). A crowded cell's points are
   * split into boxes, visited nearer first and skipped when beyond the bound.
   */
  void visitCell(const TreeCoord& cell, std::uint64_t rank) {
    if constexpr (kBuckets) {
      const Key key{tree_coord::toKey(cell[0]), tree_coord::toKey(cell[1]), tree_coord::toKey(cell[2])};
      if (!(visited_first_ && key == first_)) visitBucket(key);
    } else {
      withMetric([&](auto metric) { scanRun<decltype(metric)::value>(rank); });
    }
  }

  /**
   * The query's own cell in the buckets, before any walk: found by its key, and left out of the walk that
   * may follow. Returns true if the answer is then complete: nothing outside the cell can improve it.
   */
  bool visitOwnCell(const Key& cell) {
    visitBucket(cell);
    visited_first_ = true;
    first_ = cell;
    return settled(TreeCoord(cell), 0);
  }

  /** The points of a bucket (a cell's, or the outliers'). */
  void visitBucket(const Key& cell) {
    std::uint32_t n;
    const PointBox* boxes;
    const BucketPoint* points = storage_.find(cell, n, boxes);
    withMetric([&](auto metric) { scanBucket<decltype(metric)::value>(points, n, boxes); });
  }

  void offer(const float* p, std::int32_t index, std::uint32_t slot) {
    const PointHit h{pointDistance(metric_, p, q_), index, slot};
    if (double(h.distance) <= bound_) keep(h);
  }

 private:
  /** Calls f with the metric as a compile-time constant: each scan is compiled once per metric. */
  template <typename F>
  void withMetric(F&& f) const {
    switch (metric_) {
      case Metric::Euclidean:
        return f(std::integral_constant<Metric, Metric::Euclidean>());
      case Metric::EuclideanEigen:
        return f(std::integral_constant<Metric, Metric::EuclideanEigen>());
      case Metric::Manhattan:
        return f(std::integral_constant<Metric, Metric::Manhattan>());
    }
  }

  /** A run of the table: its points, or its boxes if it is crowded; each point's slot is its place. */
  template <Metric M>
  void scanRun(std::uint64_t rank) {
    const std::uint32_t begin = storage_.begin(rank), end = storage_.end(rank);
    const float* xyz = storage_.points();
    const auto scan = [&](std::uint32_t first, std::uint32_t last) {
      for (std::uint32_t i = first; i < last; ++i) {
        const float d = pointDistance(M, &xyz[3 * std::size_t(i)], q_);
        if (double(d) <= bound_) keep(PointHit{d, storage_.index(i), i});
      }
    };
    if (end - begin <= kCrowded) {
      // The points' own box bounds them tighter than the cell's.
      const float* box = storage_.runBox(rank).data();
      if (double(boxDistance<M>(box, box + 3)) <= bound_) scan(begin, end);
      return;
    }
    scanBoxes<M>(storage_.crowd(), storage_.crowdRoot(rank), scan);
  }

  /**
   * A bucket's points, through its boxes if it is crowded, then the tail added since; each point's slot is
   * its index. Holes have NaN coordinates, which no bound takes.
   */
  template <Metric M>
  void scanBucket(const BucketPoint* points, std::uint32_t n, const PointBox* boxes) {
    const auto scan = [&](std::uint32_t first, std::uint32_t last) {
      for (std::uint32_t i = first; i < last; ++i) {
        const float d = pointDistance(M, points[i].p, q_);
        if (double(d) <= bound_) keep(PointHit{d, points[i].index, std::uint32_t(points[i].index)});
      }
    };
    std::uint32_t tail = 0;  // the points after the boxed ones
    if (boxes) {
      scanBoxes<M>(boxes, 0, scan);
      tail = boxes[0].end;
    }
    scan(tail, n);
  }

  /**
   * A crowded cell's boxes from `node`, depth first, the nearer half first; a box is skipped once beyond the
   * bound. scan(begin, end) reads a leaf's points.
   */
  template <Metric M, typename Scan>
  void scanBoxes(const PointBox* nodes, std::uint32_t node, Scan&& scan) {
    std::uint32_t pending[64];  // one per level at most: the farther halves, with their distances
    float pending_distance[64];
    int top = 0;
    for (;;) {
      const PointBox& box = nodes[node];
      if (box.right == 0) {
        scan(box.begin, box.end);
      } else {
        std::uint32_t nearer = node + 1, farther = box.right;
        float near_d = boxDistance<M>(nodes[nearer]), far_d = boxDistance<M>(nodes[farther]);
        if (far_d < near_d) std::swap(nearer, farther), std::swap(near_d, far_d);
        if (mayHold(far_d, nodes[farther])) pending[top] = farther, pending_distance[top++] = far_d;
        if (mayHold(near_d, nodes[nearer])) {
          node = nearer;
          continue;
        }
      }
      while (top > 0 && !mayHold(pending_distance[top - 1], nodes[pending[top - 1]])) --top;
      if (top == 0) return;
      node = pending[--top];
    }
  }

  /**
   * A box at `distance` may hold a point the results take. Once k are kept, one at the k-th's distance must
   * have a smaller index, so a pile of equal points (sensors that write (0, 0, 0) for no return) is not
   * scanned whole: its halves split by index.
   */
  bool mayHold(float distance, const PointBox& box) const {
    if (double(distance) != bound_) return double(distance) < bound_;
    return results_.size() < k_ || box.least_index < worst().index;
  }

  /** The k-th best kept, once there are k. */
  const PointHit& worst() const { return k_ > kLargeK ? results_.front() : results_.back(); }

  /**
   * The least distance PCL could report from this query for a point in the box (see the free boxDistance).
   */
  template <Metric M>
  float boxDistance(const PointBox& box) const {
    return boxDistance<M>(box.lo, box.hi);
  }
  template <Metric M>
  float boxDistance(const float* lo, const float* hi) const {
    return pcl::fot::detail::boxDistance(M, lo, hi, q_);
  }

  /**
   * A point within the bound joins the results. Up to kLargeK, the k best are kept sorted, as FLANN keeps
   * them: the walk finds points roughly nearest first, so a new one mostly goes near the end. A larger k
   * keeps them in a heap, sorted at the end, and so do radius searches without max_nn, which keep every
   * point.
   */
  void keep(const PointHit& h) {
    if (k_ == kAllPoints) {
      results_.push_back(h);
      return;
    }
    if (k_ > kLargeK) {
      keepInHeap(h);
      return;
    }
    if (results_.size() == k_) {
      if (!(h < results_.back())) return;
      results_.pop_back();
    }
    std::size_t i = results_.size();
    results_.push_back(h);
    for (; i > 0 && h < results_[i - 1]; --i) results_[i] = results_[i - 1];
    results_[i] = h;
    if (results_.size() == k_) bound_ = std::min(limit_, double(results_.back().distance));
  }

  /** The k best in a max-heap: the k-th best on top. */
  void keepInHeap(const PointHit& h) {
    if (results_.size() == k_) {
      if (!(h < results_.front())) return;
      std::pop_heap(results_.begin(), results_.end());
      results_.back() = h;
    } else {
      results_.push_back(h);
    }
    std::push_heap(results_.begin(), results_.end());
    if (results_.size() == k_) bound_ = std::min(limit_, double(results_.front().distance));
  }

  static double shade(double d) { return d * (1.0 - 4e-6); }

  const Storage& storage_;
  float q_[3];
  double low_[3], high_[3];  // the query in cells from the grid origin, widened by its rounding
  double scale_;             // cell units to the metric's units
  Metric metric_;
  std::size_t k_;
  double limit_;
  double bound_;  // what a point must not exceed: the k-th best so far, else the limit
  std::vector<PointHit>& results_;
  bool visited_first_ = false;  // visitOwnCell() read the cell first_
  Key first_;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
