#pragma once

#include <cstdint>
#include <vector>

namespace pcl {
namespace fot {
namespace detail {

/** A point of a cell: its coordinates and its index as the user numbers it. */
struct BucketPoint {
  float p[3];
  std::int32_t index;
};

/**
 * A box of a crowded cell's points, which the searches visit nearer half first instead of scanning the cell
 * whole: a leaf, or split in two at the median of its longest side.
 */
struct PointBox {
  float lo[3], hi[3];
  std::uint32_t begin, end;  // the points, by position
  std::uint32_t right;       // the second half's box, 0 for a leaf; the first half's follows this one
  std::int32_t least_index;  // the smallest index of its points, for ties
};

/** Cells with more points than this are split into boxes. */
constexpr std::uint32_t kCrowded = 64;
/** The most points a box holds unsplit. */
constexpr std::uint32_t kCrowdLeaf = 16;

/**
 * Splits points[0, count) into boxes, appended to `boxes` in pre-order (the root first, `right` counted in
 * `boxes`), and reorders the points to match: a box's points are points[begin - first, end - first).
 */
void splitIntoBoxes(BucketPoint* points, std::uint32_t count, std::uint32_t first,
                    std::vector<PointBox>& boxes);

}  // namespace detail
}  // namespace fot
}  // namespace pcl
