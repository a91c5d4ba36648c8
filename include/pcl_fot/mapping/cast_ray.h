#pragma once

#include <cmath>
#include <cstdint>
#include <stdexcept>

#include <pcl_fot/dense/fast_occ_mesh.h>
#include <pcl_fot/mapping/ray_traversal.h>
#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

namespace detail {

/** The cells a map can hold, as a closed key box: where a ray may stop looking. */
inline void keyBounds(const FastOctTree& t, Key& lo, Key& hi) {
  const NodeView root = t.root();
  const std::uint32_t last = tree_coord::lowMask(root.level);
  lo = root.corner.key();
  hi = TreeCoord(root.corner[0] + last, root.corner[1] + last, root.corner[2] + last).key();
}

inline void keyBounds(const FastOccMesh& g, Key& lo, Key& hi) {
  lo = g.getMinKey();
  const std::int32_t last = std::int32_t(g.getSide()) - 1;
  hi = Key{lo.x + last, lo.y + last, lo.z + last};
}

/** A reader with the same face for both maps: the tree's through LineBurstAccess. */
struct TreeReader {
  explicit TreeReader(const FastOctTree& t) : accessor(t) {}
  CellState get(const Key& k) { return accessor.getCell(k); }
  ConstAccessor accessor;
};
struct GridReader {
  explicit GridReader(const FastOccMesh& g) : grid(g) {}
  CellState get(const Key& k) { return grid.getCell(k); }
  const FastOccMesh& grid;
};
inline TreeReader reader(const FastOctTree& t) {
  return TreeReader(t);
}
inline GridReader reader(const FastOccMesh& g) {
  return GridReader(g);
}

}  // namespace detail

/**
 * Follows the ray from `origin` along `direction` (map frame; need not be a unit vector) through the
 * cells, as OctoMap's castRay does, and stops at the first cell that is not free, which may be the
 * origin's own cell. That cell's key is written to `hit`.
 *
 * Returns true if it stopped at an occupied cell. Returns false if it stopped at an unknown cell (unless
 * ignore_unknown, which treats unknown as free), went beyond max_range metres (zero or less: no limit), or
 * left the extent of the map. Throws std::invalid_argument for a non-finite origin or a zero direction.
 */
template <typename MapT>
bool castRay(const MapT& map, const float origin[3], const float direction[3], Key& hit,
             double max_range = -1.0, bool ignore_unknown = false) {
  const CellGrid& grid = map.getGrid();
  const double norm = std::sqrt(double(direction[0]) * direction[0] + double(direction[1]) * direction[1] +
                                double(direction[2]) * direction[2]);
  if (!(norm > 0.0) || !std::isfinite(norm))
    throw std::invalid_argument("pcl::fot::castRay: the direction must be finite and non-zero");
  Key start;
  if (!grid.pointToKey(origin[0], origin[1], origin[2], start)) {
    if (!std::isfinite(origin[0]) || !std::isfinite(origin[1]) || !std::isfinite(origin[2]))
      throw std::invalid_argument("pcl::fot::castRay: the origin is not finite");
    return false;  // beyond the key range: nothing can be stored there
  }
  Key lo, hi;
  detail::keyBounds(map, lo, hi);
  auto inside = [&](const Key& k) {
    return k.x >= lo.x && k.x <= hi.x && k.y >= lo.y && k.y <= hi.y && k.z >= lo.z && k.z <= hi.z;
  };
  auto reader = detail::reader(map);
  double rel[3], unit[3];
  for (int i = 0; i < 3; ++i) {
    rel[i] = double(origin[i]) - grid.origin()[i];
    unit[i] = direction[i] / norm;
  }
  RayWalker walker(grid, start, rel, unit);
  // Enough steps to reach the map's box from the origin and cross it: the walk always ends.
  const std::int64_t span = std::int64_t(hi.x) - lo.x + std::int64_t(hi.y) - lo.y + std::int64_t(hi.z) - lo.z;
  std::int64_t budget = span + std::llabs(std::int64_t(start.x) - lo.x) +
                        std::llabs(std::int64_t(start.y) - lo.y) + std::llabs(std::int64_t(start.z) - lo.z) +
                        3;
  double entry = 0.0;  // distance at which the ray enters the current cell
  bool was_inside = inside(start);
  for (;;) {
    if (max_range > 0.0 && entry > max_range) return false;
    const Key k = walker.key();
    const bool in = inside(k);
    const CellState s = in ? reader.get(k) : CellState::Unknown;  // outside the map all is unknown
    if (s == CellState::Occupied || (s == CellState::Unknown && !ignore_unknown)) {
      hit = k;
      return s == CellState::Occupied;
    }
    if (!in && was_inside) return false;  // left the map's extent
    was_inside = was_inside || in;
    if (--budget <= 0) return false;
    entry = walker.exitDistance();
    walker.step();
  }
}

}  // namespace fot
}  // namespace pcl
