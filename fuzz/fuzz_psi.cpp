// Fuzz target: ψ against brute force. The input picks the options (free cells too, a cap, one or two
// threads) and a spacing, then writes cells and boxes of either state into two maps: near each other or
// far apart, solid or sparse, collapsed or not. ψ must equal the brute-force sum exactly, and be undefined
// exactly when brute force says so.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <vector>

#include <pcl_fot/psi/psi.h>

namespace {

using pcl::fot::CellState;
using pcl::fot::Key;

constexpr std::int64_t kNoCap = std::numeric_limits<std::int64_t>::max();

std::int64_t manhattan(const Key& a, const Key& b) {
  return std::llabs(std::int64_t(a.x) - b.x) + std::llabs(std::int64_t(a.y) - b.y) +
         std::llabs(std::int64_t(a.z) - b.z);
}

/** d(a, b) of eq. 2 by brute force: each cell of a to its nearest of b, at most cap. */
std::uint64_t directed(const std::vector<Key>& a, const std::vector<Key>& b, std::int64_t cap) {
  std::uint64_t sum = 0;
  for (const Key& p : a) {
    std::int64_t best = kNoCap;
    for (const Key& q : b) best = std::min(best, manhattan(p, q));
    sum += std::uint64_t(std::min(best, cap));
  }
  return sum;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::int64_t kCaps[] = {kNoCap, 0, 1, 3, 8, 17, 40, 1000};
  static const int kSpacings[] = {1, 2, 3, 7, 16, 33, 100, 1000};
  if (size < 2) return 0;
  pcl::fot::PsiOptions options;
  options.include_free = data[0] & 1;
  options.cap = kCaps[(data[0] >> 1) & 7];
  options.threads = 1 + ((data[0] >> 4) & 1);
  const int spacing = kSpacings[data[1] & 7];

  // Each 5 bytes: map, state and whether a box (bits of the first), a corner, and a box's side.
  pcl::fot::FastOctTree a(0.1), b(0.1);
  std::size_t budget = 6000;  // cells in boxes, so that brute force stays quick
  for (std::size_t i = 2; i + 5 <= size; i += 5) {
    pcl::fot::FastOctTree& map = data[i] & 1 ? b : a;
    const CellState state = data[i] & 2 ? CellState::Free : CellState::Occupied;
    const Key lo{std::int8_t(data[i + 1]) * spacing, std::int8_t(data[i + 2]) * spacing,
                 std::int8_t(data[i + 3]) * spacing};
    if (!(data[i] & 4)) {
      map.setCell(lo, state);
      continue;
    }
    const std::int32_t side = 1 + data[i + 4] % 12;
    if (std::size_t(side * side * side) > budget) continue;
    budget -= std::size_t(side * side * side);
    map.setBox(lo, Key{lo.x + side - 1, lo.y + side - 1, lo.z + side - 1}, state);
  }

  std::uint64_t sum = 0;
  bool defined = true;
  for (CellState v : {CellState::Occupied, CellState::Free}) {
    if (v == CellState::Free && !options.include_free) continue;
    std::vector<Key> in_a, in_b;
    a.forEachCell(v, [&](const Key& k) { in_a.push_back(k); });
    b.forEachCell(v, [&](const Key& k) { in_b.push_back(k); });
    if (in_a.empty() != in_b.empty()) {  // no distances: the cap stands in, or ψ is undefined
      if (options.cap == kNoCap)
        defined = false;
      else
        sum += (in_a.size() + in_b.size()) * std::uint64_t(options.cap);
      continue;
    }
    sum += directed(in_a, in_b, options.cap) + directed(in_b, in_a, options.cap);
  }
  const pcl::fot::PsiResult psi = pcl::fot::psi(a, b, options);
  if (psi.defined != defined || (defined && psi.sum != sum)) std::abort();
  return 0;
}
