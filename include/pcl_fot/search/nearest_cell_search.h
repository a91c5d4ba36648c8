#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

/**
 * Manhattan (L1) distances, or Euclidean ones, which are reported squared as in PCL. Point distances are
 * summed in float as PCL's searches sum them: Euclidean as FLANN, (dx² + dy²) + dz²; EuclideanEigen as
 * pcl::octree (Eigen's squaredNorm), dx² + (dy² + dz²). Cell distances are the same integers for both.
 */
enum class Metric { Manhattan, Euclidean, EuclideanEigen };

/** A cell found by NearestCellSearch, with its distance in cells (squared for the Euclidean metric). */
struct CellMatch {
  Key key;
  std::int64_t distance;
};

/**
 * Nearest-tree-neighbour queries at the cell level: the cells holding a state (Occupied by default) that
 * lie nearest to a query cell, in the Manhattan metric of the paper or the Euclidean one. Distances are
 * exact integers. Ties are broken by key: smaller x first, then y, then z.
 *
 * Keep one searcher per thread and ask it queries in spatial order: each query starts from the previous
 * one's path (LineBurstAccess). The tree must not change while a searcher uses it.
 */
class NearestCellSearch {
 public:
  static constexpr std::int64_t kUnbounded = std::numeric_limits<std::int64_t>::max();

  explicit NearestCellSearch(const FastOctTree& tree, Metric metric = Metric::Manhattan,
                             CellState target = CellState::Occupied);

  /** The nearest target cell within max_distance (inclusive); false if there is none. */
  bool nearest(const Key& query, CellMatch& match, std::int64_t max_distance = kUnbounded);
  /**
   * nearest() without the tie rule: a target cell at the least distance, not necessarily the smallest key.
   * Faster where only the distance counts, as in ψ: boxes that could only tie are not searched. A caller
   * that knows no target cell lies nearer than min_distance passes it, and the walk stops at the first
   * cell that near.
   */
  bool anyNearest(const Key& query, CellMatch& match, std::int64_t max_distance = kUnbounded,
                  std::int64_t min_distance = 0);
  /**
   * nearest() for many queries: matches[i] answers queries[i], with distance -1 where no target cell lies
   * within max_distance; returns how many were found. The answers are nearest()'s, in any order of the
   * queries. In the Manhattan metric the queries are taken a 16³ brick at a time, in Morton order, and the
   * target cells around a brick of several queries are dilated bit by bit, which settles every query
   * within 16 cells at once; only the rest are searched one by one. Runs over getNumberOfThreads() threads.
   */
  std::size_t nearest(const std::vector<Key>& queries, std::vector<CellMatch>& matches,
                      std::int64_t max_distance = kUnbounded);
  /** The k nearest target cells within max_distance, nearest first; returns how many. */
  std::size_t nearestK(const Key& query, std::size_t k, std::vector<CellMatch>& matches,
                       std::int64_t max_distance = kUnbounded);
  /** Every target cell within `radius` (inclusive), nearest first; returns how many. */
  std::size_t radius(const Key& query, std::int64_t radius, std::vector<CellMatch>& matches);

  const FastOctTree& tree() const { return tree_; }
  Metric metric() const { return metric_; }
  CellState target() const { return target_; }

  /**
   * Threads for the batch query: 1 (the default) runs it in the caller's thread, 0 takes every hardware
   * thread, and at most four per hardware thread are used. The answers do not depend on the count.
   */
  void setNumberOfThreads(unsigned threads) { threads_ = threads; }
  unsigned getNumberOfThreads() const { return threads_; }

 private:
  /** A cell found so far: ordered by distance, then by key (tree coordinates sort as keys do). */
  struct Candidate {
    std::int64_t distance;
    TreeCoord cell;
    bool operator<(const Candidate& o) const {
      if (distance != o.distance) return distance < o.distance;
      if (cell[0] != o.cell[0]) return cell[0] < o.cell[0];
      if (cell[1] != o.cell[1]) return cell[1] < o.cell[1];
      return cell[2] < o.cell[2];
    }
  };
  class Measure;
  class NearestOne;
  class NearestK;

  bool findNearest(const Key& query, CellMatch& match, std::int64_t max_distance, bool tie_rule,
                   std::int64_t floor);
  /** Fills heap_ with the best candidates, sorted; reuses its storage from query to query. */
  void search(const Key& query, std::size_t k, std::int64_t bound);
  std::size_t copyMatches(std::vector<CellMatch>& matches) const;

  const FastOctTree& tree_;
  Metric metric_;
  CellState target_;
  ConstAccessor accessor_;
  std::vector<Candidate> heap_;
  Key previous_;  // the last nearest cell: the next query's first candidate
  bool has_previous_ = false;
  unsigned threads_ = 1;
};

}  // namespace fot
}  // namespace pcl
