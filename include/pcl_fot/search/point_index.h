#pragma once

#include <cstddef>
#include <cstdint>
#include <variant>
#include <vector>

#include <pcl_fot/search/cell_buckets.h>
#include <pcl_fot/search/nearest_cell_search.h>
#include <pcl_fot/search/ranked_table.h>
#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

/**
 * Exact nearest-neighbour queries on a point set: a FastOctTree of the points' cells, plus a storage of
 * each occupied cell's points. The tree walk (see NeighbourWalk) visits cells nearest first and prunes by
 * cell boxes; a build stores the points in a compact table (detail::RankedTable), each cell's points
 * contiguous, found by the cell's rank in the tree's Morton order. A crowded cell's points are split further
 * into boxes of the points themselves.
 *
 * Distances are those PCL's searches report: squared Euclidean, (dx² + dy²) + dz² in float, or Manhattan,
 * (|dx| + |dy|) + |dz|. Results are exact, nearest first, and ties go to the smaller point index.
 * Const queries are safe from many threads at once; each thread reuses its own path from query to query.
 *
 * The index updates in place: add, remove and removeBox. The first update turns the table into one bucket
 * of points per cell, which later updates change point by point (detail::CellBuckets); build makes it a
 * table again. Queries read either storage through the same policy (point_policy.h). Results after any
 * updates equal those of a fresh build of the points held. An update needs the index alone: no query may run
 * during one.
 */
class PointIndex {
 public:
  /**
   * An index that picks its cell edge at each build: the finest at which the occupied cells hold 8 points
   * on average, where k-NN and radius searches run about fastest (doc/benchmarks.md). It counts cells on up
   * to 65,536 of the points, evenly spaced in the input, and estimates beyond; if the tree then holds fewer
   * than 4 points per cell, it takes the edge from the tree's exact counts and inserts the points again.
   */
  PointIndex();
  /**
   * A fixed cell edge. Throws std::invalid_argument for one CellGrid refuses (see CellGrid::whyInvalid).
   */
  explicit PointIndex(double resolution);

  /**
   * Indexes the points at `xyz` (point i's x, y, z at byte offset i * stride_bytes), or only those whose
   * indices `subset` lists. Points that are not finite are left out.
   */
  void build(const float* xyz, std::size_t count, std::size_t stride_bytes,
             const std::int32_t* subset = nullptr, std::size_t subset_size = 0);

  /**
   * Adds points `first_index + i` (point i at byte offset i * stride_bytes); those that are not finite are
   * left out. An empty index first centres its grid on these points (and picks its edge, if automatic).
   * Returns how many were added. Throws std::invalid_argument, adding none, if a finite point's index is
   * held already or would pass INT32_MAX, or first_index is negative.
   */
  std::size_t add(const float* xyz, std::size_t count, std::size_t stride_bytes, std::int32_t first_index);
  /**
   * Adds point i (at byte offset i * stride_bytes) as index `indices[i]`, or leaves it out if that is
   * negative or the point is not finite: a caller may give the indices of removed points again, so that
   * the table by index stays as long as the most points held at once (FastOctTreeSearch does). Returns how
   * many were added. Throws std::invalid_argument, adding none, if an index is held already or given twice.
   */
  std::size_t add(const float* xyz, std::size_t count, std::size_t stride_bytes, const std::int32_t* indices);
  /**
   * Removes the points with these indices; returns how many of them were held. If `removed` is given, their
   * indices are appended to it, each once.
   */
  std::size_t remove(const std::int32_t* indices, std::size_t count,
                     std::vector<std::int32_t>* removed = nullptr);
  /**
   * Removes the points inside the box [lo, hi], bounds included, or with inside = false those outside it;
   * returns how many, and appends their indices to `removed` if it is given.
   */
  std::size_t removeBox(const float lo[3], const float hi[3], bool inside,
                        std::vector<std::int32_t>* removed = nullptr);

  /** Points indexed: the finite ones of those given to build, then added and not removed. */
  std::size_t size() const {
    return std::visit([](const auto& storage) { return storage.size(); }, storage_);
  }
  /** The index, as given, of one point indexed; -1 if none is. */
  std::int32_t anyPoint() const { return any_; }
  /** The cell edge: the one given, or the one the last build picked (0.01 m before the first). */
  double resolution() const { return resolution_; }
  bool automatic() const { return automatic_; }
  const FastOctTree& tree() const { return tree_; }

  /**
   * The k nearest points to q, nearest first: their indices (as given to build) and distances. Returns how
   * many; 0 for a query that is not finite.
   */
  std::size_t nearestK(const float q[3], std::size_t k, Metric metric, std::vector<std::int32_t>& indices,
                       std::vector<float>& distances) const;
  /**
   * Every point within `radius` metres of q (inclusive), nearest first, or the max_results nearest of them if
   * max_results is not 0. The distances reported are those of the metric (squared for Euclidean).
   */
  std::size_t radiusSearch(const float q[3], double radius, Metric metric, std::vector<std::int32_t>& indices,
                           std::vector<float>& distances, std::size_t max_results = 0) const;

  /** Bytes held: the tree, the table and the points' copies. */
  std::size_t getMemoryBytes() const;

 private:
  class Input;
  struct Extent;
  struct Placement;
  /** Builds the tree of the points' cells, its grid centred on them (or on their bulk). */
  void placePoints(const Input& in, Extent& extent, Placement& placed);
  /**
   * Moves the points into buckets, for the updates, their indices raised by `offset`, or each index i
   * replaced by renumber[i].
   */
  void makeUpdatable(std::int32_t offset, const std::int32_t* renumber = nullptr);
  /** The buckets, once makeUpdatable has made them. */
  detail::CellBuckets& buckets() { return std::get<detail::CellBuckets>(storage_); }
  /** An automatic index whose cells hold far more or fewer points than it picks them for is built anew. */
  void refitGrid();
  /** Marks a change: the changed crowded buckets are split anew, and each thread's cached path and previous
   * answer belong to the build before. */
  void changed();
  std::size_t search(const float q[3], std::size_t k, double bound, Metric metric,
                     std::vector<std::int32_t>& indices, std::vector<float>& distances) const;

  bool automatic_;
  double resolution_;
  FastOctTree tree_;
  std::uint64_t build_id_ = 0;  // tells each thread's cached path which build it belongs to
  // The points of the tree's cells: ranked runs from a build, buckets once updated. Both keep the outliers,
  // finite points beyond the key range, which every search scans.
  std::variant<detail::RankedTable, detail::CellBuckets> storage_;
  std::int32_t any_ = -1;  // anyPoint()
};

}  // namespace fot
}  // namespace pcl
