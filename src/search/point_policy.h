#pragma once
// PointIndex's query policy: the distances from one query point to the points of the cells the tree walk
// (NeighbourWalk) visits, in the ranked table or in the buckets. Included by point_index.cpp only.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#include <pcl_fot/search/point_index.h>

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

}  // namespace detail

/** Distances from one query point, in metres, to the points of the cells the walk visits. */
class PointIndex::Policy {
 public:
  using Distance = double;

  /** `qc`: the query in cells from the grid origin, where boxes are measured; one scale turns them into
   * metres. */
  Policy(const PointIndex& index, const float q[3], const double qc[3], Metric metric, std::size_t k,
         double limit, std::vector<detail::PointHit>& results)
      : index_(index),
        q_{q[0], q[1], q[2]},
        metric_(metric),
        k_(k),
        limit_(limit),
        bound_(limit),
        results_(results) {
    const double res = index.tree_.getGrid().resolution();
    scale_ = metric != Metric::Manhattan ? res * res : res;
    const double slack =
        0x1p-48 * std::max({std::abs(qc[0]), std::abs(qc[1]), std::abs(qc[2])}) + 1e-22 / res;
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
  /** The box of the node's points bounds them tighter than the node's cube: queries far away prune more. */
  bool mayImprove(Distance, const TreeCoord&, unsigned, std::size_t word) const {
    if (word == detail::kNoWord || index_.word_box_.empty()) return true;
    const float* box = index_.word_box_[word].data();
    const float d = detail::boxDistance(metric_, box, box + 3, q_);
    return !(double(d) > bound_);
  }
  bool settled(const TreeCoord& lo, unsigned level) const { return bound_ < exterior(lo, level); }
  bool wholeRegions() const { return false; }
  void visitRegion(const TreeCoord&, unsigned, std::uint64_t) {}

  /**
   * A cell's points, or the outliers' (the run after the last cell). A crowded run is split into boxes (see
   * build), visited nearer first and skipped when beyond the bound.
   */
  void visitCell(const TreeCoord& cell, std::uint64_t rank) {
    if (index_.updatable_) {
      const Key key{tree_coord::toKey(cell[0]), tree_coord::toKey(cell[1]), tree_coord::toKey(cell[2])};
      if (!(visited_first_ && key == first_)) visitBucket(key);
      return;
    }
    const std::uint32_t begin = index_.start_[rank], end = index_.start_[rank + 1];
    withMetric([&](auto metric) { scanRun<decltype(metric)::value>(rank, begin, end); });
  }

  /**
   * The query's own cell in an updated index, before any walk: found by its key, and left out of the walk
   * that may follow. Returns true if the answer is then complete: nothing outside the cell can improve it.
   */
  bool visitOwnCell(const Key& cell) {
    visitBucket(cell);
    visited_first_ = true;
    first_ = cell;
    return settled(TreeCoord(cell), 0);
  }

  /** The points of a cell (or the outliers) in an updated index. */
  void visitBucket(const Key& cell) {
    std::uint32_t n;
    const detail::PointBox* boxes;
    const detail::BucketPoint* points = index_.buckets_.find(cell, n, boxes);
    withMetric([&](auto metric) { scanBucket<decltype(metric)::value>(points, n, boxes); });
  }

  /** k for every point within the bound. */
  static constexpr std::size_t kAll = std::numeric_limits<std::size_t>::max();
  /**
   * Beyond this k, insertion in order, O(k) a point, costs more than a heap's O(log k) and a sort at the end:
   * callgrind put the crossover at k = 70 to 80 on a Kinect frame and a room scan.
   */
  static constexpr std::size_t kLargeK = 80;

  void offer(const float* p, std::int32_t index, std::uint32_t slot) {
    const detail::PointHit h{detail::pointDistance(metric_, p, q_), index, slot};
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

  template <Metric M>
  void scanRun(std::uint64_t rank, std::uint32_t begin, std::uint32_t end) {
    const float* xyz = index_.xyz_.data();
    if (end - begin <= detail::kCrowded) {
      // The points' own box bounds them tighter than the cell's.
      const float* box = index_.run_box_[rank].data();
      if (double(boxDistance<M>(box, box + 3)) > bound_) return;
      for (std::uint32_t i = begin; i < end; ++i) consider<M>(xyz, i);
      return;
    }
    const auto& roots = index_.crowd_root_;
    const auto root = std::lower_bound(roots.begin(), roots.end(), std::make_pair(std::uint32_t(rank), 0u));
    scanBoxes<M>(index_.crowd_.data(), root->second, [&](std::uint32_t first, std::uint32_t last) {
      for (std::uint32_t i = first; i < last; ++i) consider<M>(xyz, i);
    });
  }

  /**
   * A bucket's points, through its boxes if it is crowded, then the tail added since; each point's slot is
   * its index. Holes have NaN coordinates, which no bound takes.
   */
  template <Metric M>
  void scanBucket(const detail::BucketPoint* points, std::uint32_t n, const detail::PointBox* boxes) {
    const auto scan = [&](std::uint32_t first, std::uint32_t last) {
      for (std::uint32_t i = first; i < last; ++i) {
        const float d = detail::pointDistance(M, points[i].p, q_);
        if (double(d) <= bound_) keep(detail::PointHit{d, points[i].index, std::uint32_t(points[i].index)});
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
  void scanBoxes(const detail::PointBox* nodes, std::uint32_t node, Scan&& scan) {
    std::uint32_t pending[64];  // one per level at most: the farther halves, with their distances
    float pending_distance[64];
    int top = 0;
    for (;;) {
      const detail::PointBox& box = nodes[node];
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
  bool mayHold(float distance, const detail::PointBox& box) const {
    if (double(distance) != bound_) return double(distance) < bound_;
    return results_.size() < k_ || box.least_index < worst().index;
  }

  /** The k-th best kept, once there are k. */
  const detail::PointHit& worst() const { return k_ > kLargeK ? results_.front() : results_.back(); }

  /**
   * The least distance PCL could report from this query for a point in the box (see the free boxDistance).
   */
  template <Metric M>
  float boxDistance(const detail::PointBox& box) const {
    return boxDistance<M>(box.lo, box.hi);
  }
  template <Metric M>
  float boxDistance(const float* lo, const float* hi) const {
    return detail::boxDistance(M, lo, hi, q_);
  }

  /** The distance PCL would report for the point in slot i, kept if it is within the bound. */
  template <Metric M>
  void consider(const float* xyz, std::uint32_t i) {
    const float d = detail::pointDistance(M, &xyz[3 * std::size_t(i)], q_);
    if (double(d) <= bound_) keep(detail::PointHit{d, index_.index_[i], i});
  }

  /**
   * A point within the bound joins the results. Up to kLargeK, the k best are kept sorted, as FLANN keeps
   * them: the walk finds points roughly nearest first, so a new one mostly goes near the end. A larger k
   * keeps them in a heap, sorted at the end, and so do radius searches without max_nn, which keep every
   * point.
   */
  void keep(const detail::PointHit& h) {
    if (k_ == kAll) {
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
  void keepInHeap(const detail::PointHit& h) {
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

  const PointIndex& index_;
  float q_[3];
  double low_[3], high_[3];  // the query in cells from the grid origin, widened by its rounding
  double scale_;             // cell units to the metric's units
  Metric metric_;
  std::size_t k_;
  double limit_;
  double bound_;  // what a point must not exceed: the k-th best so far, else the limit
  std::vector<detail::PointHit>& results_;
  bool visited_first_ = false;  // visitOwnCell() read the cell first_
  Key first_;
};

}  // namespace fot
}  // namespace pcl
