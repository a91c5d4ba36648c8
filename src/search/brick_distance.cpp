#include "search/brick_distance.h"

#include <algorithm>

namespace pcl {
namespace fot {
namespace detail {

namespace {

/** Cache slots for a tree of `words` node words: about one per eight, a power of two from 64 to `most`. */
std::size_t slotsFor(std::size_t words, std::size_t most) {
  std::size_t slots = 64;
  while (slots < most && slots * 8 < words) slots *= 2;
  return slots;
}

}  // namespace

PartCache::PartCache(const FastOctTree& tree, CellState state)
    : tree_(tree),
      state_(state),
      cells_(tree),
      mask_(slotsFor(tree.poolWords(), kMaxSlots) - 1),
      tags_(mask_ + 1, Tag{{0, 0, 0}, Held::Nothing}),
      words_(new std::uint64_t[(mask_ + 1) * Part::kWords]) {}

void PartCache::read(std::uint32_t x, std::uint32_t y, std::uint32_t z, Part& out) {
  const NodeWord* words = tree_.words();
  const NodeView root = tree_.root();
  if (root.level <= 3) {  // the whole tree fits one part: it lies inside this one or outside it
    const TreeCoord& base = root.corner;
    if (((base[0] - x) | (base[1] - y) | (base[2] - z)) < 8)
      out.setFromWord(words, root.word, root.level, base[0] - x, base[1] - y, base[2] - z, state_);
  } else {
    const TreeCoord c(x, y, z);
    const unsigned bottom = cells_.locatePath(c.key());
    if (bottom > 3) {  // inside a uniform octant at least as large as the part
      if (node::state(words[cells_.pathOffset(bottom)], c.octant(bottom)) == state_)
        out.bits.fill(~std::uint64_t(0));
    } else if (bottom != 0) {
      out.setFromWord(words, words[cells_.pathOffset(3)], 3, 0, 0, 0, state_);
    }
  }
}

const std::uint64_t* PartCache::part(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  const std::size_t slot = ((x >> 3) * 0x9E3779B1u ^ (y >> 3) * 0x85EBCA77u ^ (z >> 3) * 0xC2B2AE3Du) & mask_;
  Tag& tag = tags_[slot];
  std::uint64_t* bits = words_.get() + slot * Part::kWords;
  if (tag.held == Held::Nothing || tag.corner[0] != x || tag.corner[1] != y || tag.corner[2] != z) {
    Part p;
    read(x, y, z, p);
    std::copy(p.bits.begin(), p.bits.end(), bits);
    tag = Tag{{x, y, z}, p.any() ? Held::Cells : Held::EmptyPart};
  }
  return tag.held == Held::Cells ? bits : nullptr;
}

template <unsigned Reach>
bool BrickWindow<Reach>::load(PartCache& parts, const std::uint32_t lo[3]) {
  Row* r = rows(kTargets);
  std::fill(r, r + kWindow * kWindow, Row(0));
  bool any = false;
  constexpr unsigned kParts = kWindow / 8;
  for (unsigned k = 0; k < kParts; ++k)
    for (unsigned j = 0; j < kParts; ++j)
      for (unsigned i = 0; i < kParts; ++i) {
        const std::uint64_t* p = parts.part(lo[0] + 8 * i, lo[1] + 8 * j, lo[2] + 8 * k);
        if (!p) continue;
        any = true;
        for (unsigned z = 0; z < 8; ++z) {
          const std::uint64_t slice = p[z];  // row y of this slice is byte y
          if (!slice) continue;
          Row* at = r + (8 * k + z) * kWindow + 8 * j;
          for (unsigned y = 0; y < 8; ++y) at[y] |= Row((slice >> (8 * y)) & 0xFFu) << (8 * i);
        }
      }
  return any;
}

namespace {

// The dilation is plain bit logic on many rows: where the CPU has AVX2, a build of the loop for it takes
// twice the rows per instruction. It is chosen at run time, not by ifunc (target_clones): the loader runs
// ifunc resolvers before ThreadSanitizer's runtime is ready, and the program crashes.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PCL_FOT_AVX2_PATH 1
#endif

/** One dilation step over the rows [step, W - step)² of a W × W × W window; see BrickWindow::dilate. */
template <typename Row>
__attribute__((always_inline)) inline void dilateRows(const Row* __restrict in, Row* __restrict out,
                                                      std::size_t w, std::size_t step) {
  for (std::size_t z = step; z < w - step; ++z) {
    const Row* __restrict c = in + z * w;
    const Row* __restrict below = c - w;
    const Row* __restrict above = c + w;
    Row* __restrict o = out + z * w;
    for (std::size_t y = step; y < w - step; ++y)
      o[y] = c[y] | Row(c[y] << 1) | Row(c[y] >> 1) | c[y - 1] | c[y + 1] | below[y] | above[y];
  }
}

#ifdef PCL_FOT_AVX2_PATH
__attribute__((target("avx2"))) void dilateRowsAvx2(const std::uint32_t* in, std::uint32_t* out,
                                                    std::size_t w, std::size_t step) {
  dilateRows(in, out, w, step);
}
__attribute__((target("avx2"))) void dilateRowsAvx2(const std::uint64_t* in, std::uint64_t* out,
                                                    std::size_t w, std::size_t step) {
  dilateRows(in, out, w, step);
}
bool hasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

template <typename Row>
void dilateStep(const Row* in, Row* out, std::size_t w, std::size_t step) {
#ifdef PCL_FOT_AVX2_PATH
  if (hasAvx2()) {
    dilateRowsAvx2(in, out, w, step);
    return;
  }
#endif
  dilateRows(in, out, w, step);
}

}  // namespace

template <unsigned Reach>
auto BrickWindow<Reach>::dilate(unsigned step) -> const Row* {
  // Step 1 reads the tree's cells, later steps the buffer the previous one wrote. Errors from the unseen
  // outside move inwards one row per step: later steps read only [step, kWindow - step).
  Row* out = rows((step & 1u) ^ 1u);
  dilateStep(rows(step == 1 ? kTargets : (step & 1u)), out, kWindow, step);
  return out;
}

template class BrickWindow<8>;
template class BrickWindow<16>;

}  // namespace detail
}  // namespace fot
}  // namespace pcl
