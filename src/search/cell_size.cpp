#include "search/cell_size.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <pcl_fot/detail/bits.h>

namespace pcl {
namespace fot {
namespace detail {
namespace {

constexpr unsigned kLevels = 21;  // bits per axis of a 63-bit Morton code

/**
 * Cells holding `total` points of which a fraction `kept` was sampled, `hit` of them by the sample: the
 * count at which cells of equal occupancy would be hit that often, 1 - (1 - kept)^(points per cell) each.
 */
double estimateCells(double hit, double total, double kept) {
  double low = hit, high = total;
  for (int i = 0; i < 64; ++i) {
    const double mid = 0.5 * (low + high);
    if (mid * (1.0 - std::pow(1.0 - kept, total / mid)) < hit)
      low = mid;
    else
      high = mid;
  }
  return 0.5 * (low + high);
}

/** Quartiles come from at most this many values per axis: the fences need no more precision. */
constexpr std::size_t kQuartileSample = 4096;

struct Edge {
  double edge;
  bool finest;  // the finest edge the box allows: a finer one might be better
};

/** chooseCellSize over the box [lo, hi], before the clamp; the sample's points outside it are not counted. */
Edge levelEdge(const std::vector<std::array<float, 3>>& sample, std::size_t finite_count, const double lo[3],
               const double hi[3]) {
  const double side = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const double finest = side / double(1u << kLevels);
  if (sample.empty() || !(finest > 0.0)) return {side, false};

  // In Morton order, neighbours first differ at the level below which they share a cell.
  std::vector<std::uint64_t> codes;
  codes.reserve(sample.size());
  // A level's edge only has to be about right: a point a rounding away from a cell's face may count in
  // either cell.
  const double per_cell = 1.0 / finest, last = double((1u << kLevels) - 1);
  for (const auto& p : sample) {
    if (p[0] < lo[0] || p[0] > hi[0] || p[1] < lo[1] || p[1] > hi[1] || p[2] < lo[2] || p[2] > hi[2])
      continue;
    std::uint32_t u[3];
    for (int a = 0; a < 3; ++a)  // truncation is floor here, the offsets being positive
      u[a] = std::uint32_t(std::min((double(p[a]) - lo[a]) * per_cell, last));
    codes.push_back(morton3(u[0], u[1], u[2]));
  }
  if (codes.empty()) return {side, false};
  std::sort(codes.begin(), codes.end());
  std::size_t splits[kLevels + 1] = {};  // neighbours in separate cells up to this level, not above
  for (std::size_t i = 1; i < codes.size(); ++i)
    if (const std::uint64_t d = codes[i] ^ codes[i - 1]) ++splits[detail::highestBit(d) / 3];

  const double kept = double(sample.size()) / double(finite_count), total = double(codes.size()) / kept;
  std::size_t hit = 1;  // the sample's cells at level l
  for (std::size_t s : splits) hit += s;
  for (unsigned l = 0; l <= kLevels; hit -= splits[l], ++l) {
    const double cells = kept >= 1.0 ? double(hit) : estimateCells(double(hit), total, kept);
    if (total >= kPointsPerCell * cells) return {std::ldexp(finest, int(l)), l == 0};
  }
  return {side, false};
}

/** Adds to blocks[k], for each level k up to `level`, the blocks below w that hold an occupied cell. */
void countBlocks(const NodeWord* words, NodeWord w, unsigned level, std::vector<double>& blocks) {
  if (node::isBitmap(w)) {
    const unsigned octants = node::popcount(node::octantMask(w, CellState::Occupied));
    if (octants == 0) return;
    blocks[level] += 1.0;
    for (unsigned k = 0; k < level; ++k) blocks[k] += std::ldexp(double(octants), int(3 * (level - 1 - k)));
    return;
  }
  blocks[level] += 1.0;  // a point index's tree branches only towards occupied cells
  for (unsigned o = 0; o < 8; ++o) countBlocks(words, words[node::childOffset(w, o)], level - 1, blocks);
}

}  // namespace

double coarserCellSize(const FastOctTree& tree, std::size_t points) {
  std::vector<double> blocks(tree.getDepth() + 1, 0.0);
  countBlocks(tree.words(), tree.root().word, tree.getDepth(), blocks);
  unsigned k = 1;
  while (k < tree.getDepth() && double(points) < kPointsPerCell * blocks[k]) ++k;
  return std::clamp(std::ldexp(tree.getResolution(), int(k)), kFinestCell, kCoarsestCell);
}

void bulkBox(const std::vector<std::array<float, 3>>& sample, const double lo[3], const double hi[3],
             double bulk_lo[3], double bulk_hi[3]) {
  std::copy(lo, lo + 3, bulk_lo);
  std::copy(hi, hi + 3, bulk_hi);
  if (sample.empty()) return;
  const std::size_t m = std::min(sample.size(), kQuartileSample);
  std::vector<double> v(m);
  for (int a = 0; a < 3; ++a) {
    for (std::size_t s = 0; s < m; ++s) v[s] = sample[s * sample.size() / m][std::size_t(a)];
    const auto q1 = v.begin() + std::ptrdiff_t((m - 1) / 4), q3 = v.begin() + std::ptrdiff_t(3 * (m - 1) / 4);
    std::nth_element(v.begin(), q1, v.end());
    std::nth_element(q1, q3, v.end());
    const double range = *q3 - *q1;
    bulk_lo[a] = std::max(lo[a], *q1 - 3.0 * range);
    bulk_hi[a] = std::min(hi[a], *q3 + 3.0 * range);
  }
}

double chooseCellSize(const std::vector<std::array<float, 3>>& sample, std::size_t finite_count,
                      const double lo[3], const double hi[3]) {
  Edge e = levelEdge(sample, finite_count, lo, hi);
  if (e.finest) {
    double bulk_lo[3], bulk_hi[3];
    bulkBox(sample, lo, hi, bulk_lo, bulk_hi);
    const Edge bulk = levelEdge(sample, finite_count, bulk_lo, bulk_hi);
    if (bulk.edge > 0.0) e.edge = std::min(e.edge, bulk.edge);
  }
  return std::clamp(e.edge, kFinestCell, kCoarsestCell);
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
