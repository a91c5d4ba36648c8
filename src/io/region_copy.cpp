#include "io/region_copy.h"

#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace pcl {
namespace fot {
namespace io {

double boxCubes(const Key& lo, const Key& hi) {
  const TreeCoord l(lo), h(hi);
  double cubes = 0;
  for (unsigned level = 0; level < 32; ++level) {
    // Per axis: a = aligned cells of the next level inside the box, r = those of this level beside them
    // (0, 1 or 2, at the ends). This level's cubes whose parent is not inside: (2a + r)^3 - 8a^3, term by
    // term.
    double a[3], r[3];
    for (unsigned axis = 0; axis < 3; ++axis) {
      const std::uint64_t first = l[axis], end = std::uint64_t(h[axis]) + 1;
      auto inside = [&](unsigned lv) -> std::uint64_t {
        const std::uint64_t from = (first + (std::uint64_t(1) << lv) - 1) >> lv, to = end >> lv;
        return to > from ? to - from : 0;
      };
      const std::uint64_t n = inside(level), parents = inside(level + 1);
      a[axis] = double(parents);
      r[axis] = double(n - 2 * parents);
    }
    cubes += 4 * (r[0] * a[1] * a[2] + a[0] * r[1] * a[2] + a[0] * a[1] * r[2]) +
             2 * (r[0] * r[1] * a[2] + r[0] * a[1] * r[2] + a[0] * r[1] * r[2]) + r[0] * r[1] * r[2];
  }
  return cubes;
}

FastOctTree shiftedCopy(const FastOctTree& from, const CellGrid& grid, const std::int64_t shift[3],
                        std::size_t max_pool_bytes) {
  struct Box {
    Key lo, hi;
    float log_odds;
  };
  std::vector<Box> boxes;
  double cubes = 0;
  from.forEachLogOdds([&](const Region& r, float v) {
    const std::int64_t last = (std::int64_t(1) << r.level) - 1;
    const std::int64_t lo[3] = {r.min_key.x + shift[0], r.min_key.y + shift[1], r.min_key.z + shift[2]};
    for (std::int64_t c : lo)
      if (c < kMinKey || c + last > kMaxKey)
        throw std::invalid_argument(
            "pcl::fot::io: the cells lie beyond the key range once moved to the origin");
    const Key l{std::int32_t(lo[0]), std::int32_t(lo[1]), std::int32_t(lo[2])};
    const Key h{std::int32_t(lo[0] + last), std::int32_t(lo[1] + last), std::int32_t(lo[2] + last)};
    cubes += boxCubes(l, h);
    boxes.push_back(Box{l, h, v});
  });
  // A word per cube: copies of shifted cubes measured 0.57 words per cube, in a pool that grows by doubling.
  // Beyond the cap, refuse at once rather than fill memory up to it.
  const double bytes = cubes * sizeof(NodeWord);
  if (bytes > double(max_pool_bytes)) {
    char text[200];
    std::snprintf(
        text, sizeof text,
        "pcl::fot::io: the map would need up to %.3g bytes (%.3g cubes) in this grid, beyond the cap "
        "of %zu bytes",
        bytes, cubes, max_pool_bytes);
    throw MemoryLimitError(text);
  }
  FastOctTree to(grid);
  to.setSensorModel(from.getSensorModel());
  to.setUpdateRule(from.getUpdateRule());
  to.setMaxMemoryBytes(max_pool_bytes);
  for (const Box& b : boxes) to.setBoxLogOdds(b.lo, b.hi, b.log_odds);
  to.setMaxMemoryBytes(std::numeric_limits<std::size_t>::max());
  return to;
}

}  // namespace io
}  // namespace fot
}  // namespace pcl
