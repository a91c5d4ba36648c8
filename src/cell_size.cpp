#include "cell_size.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace pcl {
namespace fot {
namespace detail {
namespace {

constexpr unsigned kLevels = 21;  // bits per axis of a 63-bit Morton code

/** Spreads the low 21 bits of v to every third bit. */
std::uint64_t spreadBits(std::uint32_t v) {
  std::uint64_t x = v & 0x1FFFFFu;
  x = (x | x << 32) & 0x1F00000000FFFFull;
  x = (x | x << 16) & 0x1F0000FF0000FFull;
  x = (x | x << 8) & 0x100F00F00F00F00Full;
  x = (x | x << 4) & 0x10C30C30C30C30C3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

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

/** chooseCellSize before the clamp. */
double levelEdge(const std::vector<std::array<float, 3>>& sample, std::size_t finite_count,
                 const double lo[3], const double hi[3]) {
  const double side = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const double finest = side / double(1u << kLevels);
  if (sample.empty() || !(finest > 0.0)) return side;

  // In Morton order, neighbours first differ at the level below which they share a cell.
  std::vector<std::uint64_t> codes;
  codes.reserve(sample.size());
  for (const auto& p : sample) {
    std::uint64_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const double u = std::min(std::floor((double(p[a]) - lo[a]) / finest), double((1u << kLevels) - 1));
      code |= spreadBits(std::uint32_t(u)) << a;
    }
    codes.push_back(code);
  }
  std::sort(codes.begin(), codes.end());
  std::size_t splits[kLevels + 1] = {};  // neighbours in separate cells up to this level, not above
  for (std::size_t i = 1; i < codes.size(); ++i)
    if (const std::uint64_t d = codes[i] ^ codes[i - 1]) ++splits[(63 - __builtin_clzll(d)) / 3];

  const double total = double(finite_count), kept = double(sample.size()) / total;
  std::size_t hit = 1;  // the sample's cells at level l
  for (std::size_t s : splits) hit += s;
  for (unsigned l = 0; l <= kLevels; hit -= splits[l], ++l) {
    const double cells = kept >= 1.0 ? double(hit) : estimateCells(double(hit), total, kept);
    if (total >= kPointsPerCell * cells) return std::ldexp(finest, int(l));
  }
  return side;
}

}  // namespace

double chooseCellSize(const std::vector<std::array<float, 3>>& sample, std::size_t finite_count,
                      const double lo[3], const double hi[3]) {
  return std::clamp(levelEdge(sample, finite_count, lo, hi), kFinestCell, kCoarsestCell);
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
