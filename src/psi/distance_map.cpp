#include <pcl_fot/psi/distance_map.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "psi/psi_sum.h"

namespace pcl {
namespace fot {
namespace {

/** d + 1, staying at kNone. */
inline std::uint16_t step(std::uint16_t d) {
  return d == DistanceMap::kNone ? d : std::uint16_t(d + 1);
}

}  // namespace

void DistanceMap::compute(const FastOccMesh& grid, CellState value) {
  if (grid.getSide() > (kNone - 1) / 3)
    throw std::invalid_argument("pcl::fot::DistanceMap: a cube of side " + std::to_string(grid.getSide()) +
                                " cells has distances beyond 16 bits");
  side_ = grid.getSide();
  min_key_ = grid.getMinKey();
  empty_ = true;
  distances_.assign(side_ * side_ * side_, kNone);
  grid.forEachCell(value, [&](const Key& k) {
    distances_[index(k)] = 0;
    empty_ = false;
  });
  if (empty_) return;
  const std::size_t n = side_, plane = n * n;
  std::uint16_t* d = distances_.data();
  // Forward: from the lower neighbours along x, y and z.
  for (std::size_t z = 0; z < n; ++z)
    for (std::size_t y = 0; y < n; ++y) {
      std::uint16_t* row = d + z * plane + y * n;
      const std::uint16_t* below_y = y ? row - n : nullptr;
      const std::uint16_t* below_z = z ? row - plane : nullptr;
      if (below_y)
        for (std::size_t x = 0; x < n; ++x) row[x] = std::min(row[x], step(below_y[x]));
      if (below_z)
        for (std::size_t x = 0; x < n; ++x) row[x] = std::min(row[x], step(below_z[x]));
      for (std::size_t x = 1; x < n; ++x) row[x] = std::min(row[x], step(row[x - 1]));
    }
  // Backward: from the upper neighbours.
  for (std::size_t z = n; z-- > 0;)
    for (std::size_t y = n; y-- > 0;) {
      std::uint16_t* row = d + z * plane + y * n;
      const std::uint16_t* above_y = y + 1 < n ? row + n : nullptr;
      const std::uint16_t* above_z = z + 1 < n ? row + plane : nullptr;
      if (above_y)
        for (std::size_t x = 0; x < n; ++x) row[x] = std::min(row[x], step(above_y[x]));
      if (above_z)
        for (std::size_t x = 0; x < n; ++x) row[x] = std::min(row[x], step(above_z[x]));
      for (std::size_t x = n - 1; x-- > 0;) row[x] = std::min(row[x], step(row[x + 1]));
    }
}

PsiResult psiByDistanceMaps(const FastOccMesh& a, const FastOccMesh& b, const PsiOptions& options) {
  DistanceMap workspace;
  return psiByDistanceMaps(a, b, workspace, options);
}

PsiResult psiByDistanceMaps(const FastOccMesh& a, const FastOccMesh& b, DistanceMap& workspace,
                            const PsiOptions& options) {
  if (a.getGrid() != b.getGrid() || a.getSide() != b.getSide() || a.getMinKey() != b.getMinKey())
    throw std::invalid_argument(
        "pcl::fot::psiByDistanceMaps: the grids must share resolution, origin and cube");
  if (options.cap < 0)
    throw std::invalid_argument("pcl::fot::psiByDistanceMaps: the cap must not be negative");
  auto count = [](const FastOccMesh& g, CellState v) {
    return v == CellState::Occupied ? g.getOccupiedCount() : g.getFreeCount();
  };
  // One distance map at a time, in the same storage: 2 GiB at 1024³.
  auto read_off = [&](const FastOccMesh& from, const FastOccMesh& to, CellState v) {
    workspace.compute(to, v);
    std::uint64_t sum = 0;
    from.forEachCell(
        v, [&](const Key& k) { sum += std::uint64_t(std::min<std::int64_t>(workspace.at(k), options.cap)); });
    return sum;
  };
  return detail::sumOverValues(
      options, a.getResolution(), [&](CellState v) { return std::make_pair(count(a, v), count(b, v)); },
      [&](CellState v) { return read_off(a, b, v) + read_off(b, a, v); });
}

}  // namespace fot
}  // namespace pcl
