#pragma once
// Private to the library: the nearest-tree-neighbour walk that the cell and the point searches share.

#include <algorithm>
#include <cstdint>
#include <cstring>

#include <pcl_fot/detail/bits.h>
#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace detail {

/**
 * The nearest-tree-neighbour walk of the paper (§IV, Algorithm IV.1), shared by the cell and the point
 * searches. The downward phase is the accessor's: it finds the deepest node holding the query, reusing
 * the previous query's path. The upward phase then searches, level by level, the siblings of the node
 * already searched, nearest box first, pruning every box that cannot beat the current result, and stops
 * as soon as nothing outside the searched node can. Collapsed regions are searched as cubes, never
 * expanded in the tree.
 *
 * The Policy knows the query and the metric and keeps the result. It provides:
 * - `Distance`, the metric's type;
 * - `childGaps(lo, child_level, gap)`: for the cube at `lo` with children of child_level, per axis, the
 *   query's distance to the lower (gap[a][0]) and upper (gap[a][1]) half, in the metric's units (squared
 *   for Euclidean); a child's lower bound sums its halves';
 * - `worthVisiting(lower_bound)`: the pruning test, and `mayImprove(lower_bound, lo, level, word)` a second
 *   one for a box that passed it (boxes are taken nearest first, so the walk stops at the first box that
 *   fails the first test, and only skips one that fails the second); `word` is the pool offset of the box's
 *   node word, or kNoWord for an octant inside a bitmap word;
 * - `settled(lo, level)`: the stopping test, true when nothing outside the query's cube at `lo` can improve
 *   the result;
 * - `wholeRegions()`: visit uniform cubes whole rather than cell by cell;
 * - `visitRegion(lo, level, rank)` and `visitCell(cell, rank)`: a target cube or cell to consider.
 * Cubes are given in tree coordinates. `rank` numbers target cells in the tree's Morton order when the walk
 * is given `ranks` (the rank of the first target cell under each bitmap word, by pool offset), else 0.
 */
/** No node word of its own: an octant of a bitmap word. */
constexpr std::size_t kNoWord = ~std::size_t(0);

template <typename Policy>
class NeighbourWalk {
 public:
  using Distance = typename Policy::Distance;

  /** `target` is Occupied or Free: the walk finds cells of one known state. */
  NeighbourWalk(const FastOctTree& tree, CellState target, const std::uint64_t* ranks, Policy& policy)
      : tree_(tree),
        words_(tree.words()),
        target_(target),
        no_targets_mask_(node::kBitmapTag | node::stateBits(target)),
        ranks_(ranks),
        policy_(policy) {}

  /** Searches around the cell `query`, which may lie anywhere, inside the tree or not. */
  void run(ConstAccessor& accessor, const Key& query) {
    words_ = tree_.words();
    const unsigned bottom = accessor.locatePath(query);
    if (bottom == 0) {  // outside the root: the root is the node to search
      const NodeView root = tree_.root();
      searchWord(root.word, 0, root.level, root.corner);
      return;
    }
    const TreeCoord q(query);
    searchAround(words_[accessor.pathOffset(bottom)], accessor.pathOffset(bottom), bottom, q.corner(bottom),
                 8);
    for (unsigned level = bottom + 1; level <= tree_.getDepth(); ++level) {
      if (policy_.settled(q.corner(level - 1), level - 1)) return;
      searchAround(words_[accessor.pathOffset(level)], accessor.pathOffset(level), level, q.corner(level),
                   q.octant(level));
    }
  }

 private:
  struct Child {
    Distance bound;
    unsigned octant;
  };

  static Distance childBound(const Distance gap[3][2], unsigned o) {
    return gap[0][o & 1u] + gap[1][(o >> 1) & 1u] + gap[2][(o >> 2) & 1u];
  }

  /** Sorts up to 8 children by their lower bounds (those already beyond the result are left out first). */
  static void order(Child* c, int n) {
    for (int i = 1; i < n; ++i)
      for (int j = i; j > 0 && c[j].bound < c[j - 1].bound; --j) std::swap(c[j], c[j - 1]);
  }

  /** The octants in `mask` of the cube at `base` (children of level `sub`) that may still beat the result,
   * nearest first; returns how many. */
  int nearestFirst(const TreeCoord& base, unsigned sub, std::uint32_t mask, Child* c) const {
    Distance gap[3][2];
    policy_.childGaps(base, sub, gap);
    int n = 0;
    for (unsigned o = 0; o < 8; ++o) {
      if (!((mask >> o) & 1u)) continue;
      const Distance bound = childBound(gap, o);
      if (policy_.worthVisiting(bound)) c[n++] = Child{bound, o};
    }
    order(c, n);
    return n;
  }

  /**
   * Octants of a reference word whose child may hold target cells: a reference, or a bitmap holding some.
   * Four children per vector operation: the walk asks this at every reference it passes.
   */
  std::uint32_t childrenWithTargets(NodeWord w) const {
    using Lanes = std::int32_t __attribute__((vector_size(16)));
    Lanes low, high;
    std::memcpy(&low, words_ + node::childOffset(w, 0), sizeof low);
    std::memcpy(&high, words_ + node::childOffset(w, 4), sizeof high);
    const Lanes keep = Lanes{} + std::int32_t(no_targets_mask_),
                tag = Lanes{} + std::int32_t(node::kBitmapTag);
    const Lanes none =
        (((low & keep) == tag) & Lanes{1, 2, 4, 8}) | (((high & keep) == tag) & Lanes{16, 32, 64, 128});
    return ~std::uint32_t(none[0] | none[1] | none[2] | none[3]) & 0xFFu;
  }

  /** A node that holds the query: its children (or octants), except `skip`, nearest first, as the paper
   * orders them. */
  void searchAround(NodeWord w, std::size_t offset, unsigned level, const TreeCoord& base, unsigned skip) {
    const bool bitmap = node::isBitmap(w);
    if (bitmap && policy_.wholeRegions()) {
      visitOctants(node::octantMask(w, target_) & ~(skip < 8 ? 1u << skip : 0u), level, base);
      return;
    }
    const unsigned sub = level - 1;
    const std::uint32_t mask = bitmap ? node::octantMask(w, target_) : childrenWithTargets(w);
    const std::uint64_t rank = (bitmap && ranks_) ? ranks_[offset] : 0;
    nearestChildren(base, sub, mask & ~(skip < 8 ? 1u << skip : 0u), bitmap ? kNoWord : node::childBase(w),
                    [&](unsigned o, const TreeCoord& lo) {
                      if (bitmap) {
                        searchRegion(lo, sub,
                                     rank + node::cellsIn(node::popcount(mask & ((1u << o) - 1u)), sub));
                      } else {
                        const std::size_t at = node::childOffset(w, o);
                        searchWord(words_[at], at, sub, lo);
                      }
                    });
  }

  /**
   * Calls visit(octant, corner) for the octants in `mask` of the cube at `base`, children of level `sub`,
   * nearest first, while they may still beat the result. `children` is the pool offset of the children's
   * words, kNoWord for the octants of a bitmap word.
   */
  template <typename Visit>
  void nearestChildren(const TreeCoord& base, unsigned sub, std::uint32_t mask, std::size_t children,
                       Visit&& visit) {
    Child c[8];
    const int n = nearestFirst(base, sub, mask, c);
    for (int i = 0; i < n; ++i) {
      if (!policy_.worthVisiting(c[i].bound)) return;
      const TreeCoord lo = base.child(c[i].octant, sub);
      if (policy_.mayImprove(c[i].bound, lo, sub, children == kNoWord ? kNoWord : children + c[i].octant))
        visit(c[i].octant, lo);
    }
  }

  /** A policy that takes cubes whole finds each octant's best cell exactly: no bounds, no order needed. */
  void visitOctants(std::uint32_t mask, unsigned level, const TreeCoord& base) {
    const unsigned sub = level - 1;
    for (unsigned o = 0; o < 8; ++o) {
      if (!((mask >> o) & 1u)) continue;
      const TreeCoord lo = base.child(o, sub);
      if (sub == 0)
        policy_.visitCell(lo, 0);
      else
        policy_.visitRegion(lo, sub, 0);
    }
  }

  /**
   * A node word: a bitmap's target octants are uniform cubes, a reference's children are searched. In sparse
   * maps a lone cell hangs below a chain of references with one child each: the walk follows it in a loop,
   * checking each link's bound, with nothing to order.
   */
  void searchWord(NodeWord w, std::size_t offset, unsigned level, const TreeCoord& base) {
    TreeCoord lo = base;
    while (!node::isBitmap(w)) {
      const std::uint32_t children = childrenWithTargets(w);
      if (children & (children - 1)) {
        searchChildren(w, children, level, lo);
        return;
      }
      if (children == 0) return;
      const unsigned o = detail::lowestBit(children), sub = level - 1;
      Distance gap[3][2];
      policy_.childGaps(lo, sub, gap);
      const Distance bound = childBound(gap, o);
      lo = lo.child(o, sub);
      if (!policy_.worthVisiting(bound) || !policy_.mayImprove(bound, lo, sub, node::childOffset(w, o)))
        return;
      offset = node::childOffset(w, o);
      w = words_[offset];
      level = sub;
    }
    searchBitmap(w, offset, level, lo);
  }

  /** A bitmap word: its target octants are uniform cubes. */
  void searchBitmap(NodeWord w, std::size_t offset, unsigned level, const TreeCoord& base) {
    const std::uint32_t mask = node::octantMask(w, target_);
    if (mask == 0) return;
    const std::uint64_t rank = ranks_ ? ranks_[offset] : 0;
    if (mask == 0xFFu) {  // one uniform cube of target cells
      searchRegion(base, level, rank);
      return;
    }
    if (policy_.wholeRegions()) {
      visitOctants(mask, level, base);
      return;
    }
    const unsigned sub = level - 1;
    nearestChildren(base, sub, mask, kNoWord, [&](unsigned o, const TreeCoord& lo) {
      searchRegion(lo, sub, rank + node::cellsIn(node::popcount(mask & ((1u << o) - 1u)), sub));
    });
  }

  /** The children of a reference word that may hold targets (`children`), nearest first. */
  void searchChildren(NodeWord w, std::uint32_t children, unsigned level, const TreeCoord& base) {
    const unsigned sub = level - 1;
    nearestChildren(base, sub, children, node::childBase(w), [&](unsigned o, const TreeCoord& lo) {
      const std::size_t at = node::childOffset(w, o);
      searchWord(words_[at], at, sub, lo);
    });
  }

  /** A uniform cube of target cells, split in its octants as far as the policy needs. */
  void searchRegion(const TreeCoord& lo, unsigned level, std::uint64_t rank) {
    if (level == 0) {
      policy_.visitCell(lo, rank);
      return;
    }
    if (policy_.wholeRegions()) {
      policy_.visitRegion(lo, level, rank);
      return;
    }
    const unsigned sub = level - 1;
    nearestChildren(lo, sub, 0xFFu, kNoWord, [&](unsigned o, const TreeCoord& child) {
      searchRegion(child, sub, rank + node::cellsIn(o, sub));
    });
  }

  const FastOctTree& tree_;
  const NodeWord* words_;
  CellState target_;
  NodeWord no_targets_mask_;  // a child word is a bitmap without targets iff (word & this) == kBitmapTag
  const std::uint64_t* ranks_;
  Policy& policy_;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
