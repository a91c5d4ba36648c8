#pragma once
// Private to the library: a tree's regions copied into another tree at shifted keys, at a cost checked first.

#include <cstddef>
#include <cstdint>

#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace io {

/**
 * The cubes FastOctTree::setBox writes for the key box [lo, hi]: the aligned cubes inside it whose parent is
 * not. Exact, in closed form per level; as a double, since a box's count can pass 2^64.
 */
double boxCubes(const Key& lo, const Key& hi);

/**
 * A tree on `grid` holding every known region of `from`, keys shifted by `shift`. A region whose cube is
 * aligned after the shift is one word; one that is not costs its surface. Throws std::invalid_argument if a
 * cell would leave the key range, and MemoryLimitError, saying about how much the copy needs, before it
 * writes anything if that passes max_pool_bytes (and, while it writes, if the copy does). The copy returned
 * has no cap.
 */
FastOctTree shiftedCopy(const FastOctTree& from, const CellGrid& grid, const std::int64_t shift[3],
                        std::size_t max_pool_bytes);

}  // namespace io
}  // namespace fot
}  // namespace pcl
