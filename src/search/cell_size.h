#pragma once
// Private to the library: how a PointIndex fits its grid to its points (their bulk, the cell edge).

#include <array>
#include <cstddef>
#include <vector>

#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace detail {

/** Points a PointIndex keeps counted exactly; beyond this it counts a sample of this many. */
constexpr std::size_t kCellSizeSample = 65536;
/** Occupied cells holding this many points on average or more search fastest (doc/benchmarks.md). */
constexpr double kPointsPerCell = 8.0;
/**
 * The edges chosen are kept within these. Below, the walk's 1e-22 m of slack (PointIndex::Policy) blurs the
 * cells; above, a grid with its origin at 0 would put cell centres beyond float's range.
 */
constexpr double kFinestCell = 1e-18, kCoarsestCell = 0x1p96;

/**
 * The box holding the bulk of the points: per axis, Tukey's far fences (three interquartile ranges beyond
 * the quartiles) of `sample`, an even sample of them, within their bounding box [lo, hi]. A few stray points
 * far away, as sensors give, barely move it, where they stretch the bounding box by orders of magnitude.
 */
void bulkBox(const std::vector<std::array<float, 3>>& sample, const double lo[3], const double hi[3],
             double bulk_lo[3], double bulk_hi[3]);

/**
 * The finest cell edge, of side / 2^l for l = 0..21 (side: the longest side of the points' bounding box
 * [lo, hi]), at which the points' occupied cells hold kPointsPerCell points on average; side itself if none
 * does; within [kFinestCell, kCoarsestCell]. When even side / 2^21 holds that many, stray points stretch the
 * box: the edges are then those of the sample's bulk box (bulkBox), counting the points inside it. `sample`
 * holds `finite_count` finite points, or an even sample of them: then the cells are counted on the sample,
 * and the full count estimated as if every cell held the same number of points.
 */
double chooseCellSize(const std::vector<std::array<float, 3>>& sample, std::size_t finite_count,
                      const double lo[3], const double hi[3]);

/**
 * The edge for `points` points in `tree`'s occupied cells: the tree's edge times the smallest 2^k at which
 * the tree's aligned blocks of 2^k cells per axis that hold any occupied cell hold kPointsPerCell points on
 * average; within [kFinestCell, kCoarsestCell].
 */
double coarserCellSize(const FastOctTree& tree, std::size_t points);

}  // namespace detail
}  // namespace fot
}  // namespace pcl
