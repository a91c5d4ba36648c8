#pragma once
// Private to the library: eq. 1 of ψ around the directed sums, shared by the tree and the dmap_v method.

#include <cstdint>
#include <limits>
#include <utility>

#include <pcl_fot/psi/psi.h>

namespace pcl {
namespace fot {
namespace detail {

/**
 * Eq. 1 around the directed sums, for either method: for each compared value, count(v) gives the two
 * maps' cell counts and both(v) the sum of d(a, b, v) and d(b, a, v). A value that only one map has
 * leaves ψ undefined, unless a cap stands in for the missing distances.
 */
template <typename Count, typename Both>
PsiResult sumOverValues(const PsiOptions& options, double resolution, Count&& count, Both&& both) {
  const bool capped = options.cap != std::numeric_limits<std::int64_t>::max();
  PsiResult result;
  result.resolution = resolution;
  for (CellState v : {CellState::Occupied, CellState::Free}) {
    if (v == CellState::Free && !options.include_free) continue;
    const std::pair<std::uint64_t, std::uint64_t> n = count(v);
    result.cells += n.first + n.second;
    if (n.first == 0 && n.second == 0) continue;
    if (n.first == 0 || n.second == 0) {
      if (capped)
        result.sum += (n.first + n.second) * std::uint64_t(options.cap);
      else
        result.defined = false;
      continue;
    }
    result.sum += both(v);
  }
  return result;
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
