#pragma once
// Private to the library: the cell edge an automatic PointIndex picks for its points.

#include <array>
#include <cstddef>
#include <vector>

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
 * The finest cell edge, of side / 2^l for l = 0..21 (side: the longest side of the points' bounding box
 * [lo, hi]), at which the points' occupied cells hold kPointsPerCell points on average; side itself if none
 * does; within [kFinestCell, kCoarsestCell]. `sample` holds `finite_count` finite points, or an even sample
 * of them: then the cells are counted on the sample, and the full count estimated as if every cell held the
 * same number of points.
 */
double chooseCellSize(const std::vector<std::array<float, 3>>& sample, std::size_t finite_count,
                      const double lo[3], const double hi[3]);

}  // namespace detail
}  // namespace fot
}  // namespace pcl
