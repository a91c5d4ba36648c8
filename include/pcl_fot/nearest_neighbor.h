#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <pcl_fot/accessor.h>
#include <pcl_fot/fast_oct_tree.h>

namespace pcl {
namespace fot {

/** Manhattan (L1) distances, or Euclidean ones, which are reported squared as in PCL. */
enum class Metric { Manhattan, Euclidean };

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
 * - `worthVisiting(lower_bound)`: the pruning test, and `mayImprove(lower_bound, lo, level)` a second one
 *   for a box that passed it (boxes are taken nearest first, so the walk stops at the first box that fails
 *   the first test, and only skips one that fails the second);
 * - `settled(lo, level)`: the stopping test, true when nothing outside the query's cube at `lo` can improve
 *   the result;
 * - `wholeRegions()`: visit uniform cubes whole rather than cell by cell;
 * - `visitRegion(lo, level, rank)` and `visitCell(cell, rank)`: a target cube or cell to consider.
 * Cubes are given in tree coordinates. `rank` numbers target cells in the tree's Morton order when the walk
 * is given `ranks` (the rank of the first target cell under each bitmap word, by pool offset), else 0.
 */
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
      searchWord(tree_.rootWord(), 0, tree_.rootLevel(), tree_.rootBase().data());
      return;
    }
    const std::uint32_t q[3] = {tree_coord::fromKey(query.x), tree_coord::fromKey(query.y),
                                tree_coord::fromKey(query.z)};
    std::uint32_t base[3];
    corner(q, bottom, base);
    searchAround(words_[accessor.pathOffset(bottom)], accessor.pathOffset(bottom), bottom, base, 8);
    for (unsigned level = bottom + 1; level <= tree_.rootLevel(); ++level) {
      if (policy_.settled(base, level - 1)) return;
      const unsigned skip = tree_coord::octant(q[0], q[1], q[2], level);
      corner(q, level, base);
      searchAround(words_[accessor.pathOffset(level)], accessor.pathOffset(level), level, base, skip);
    }
  }

 private:
  struct Child {
    Distance bound;
    unsigned octant;
  };

  static void corner(const std::uint32_t q[3], unsigned level, std::uint32_t out[3]) {
    const std::uint32_t mask = ~std::uint32_t((std::uint64_t(1) << level) - 1);
    out[0] = q[0] & mask, out[1] = q[1] & mask, out[2] = q[2] & mask;
  }

  static void childCorner(const std::uint32_t base[3], unsigned child_level, unsigned o,
                          std::uint32_t out[3]) {
    const std::uint32_t size = std::uint32_t(1) << child_level;
    out[0] = base[0] + (o & 1u) * size;
    out[1] = base[1] + ((o >> 1) & 1u) * size;
    out[2] = base[2] + ((o >> 2) & 1u) * size;
  }

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
  int nearestFirst(const std::uint32_t base[3], unsigned sub, std::uint32_t mask, Child* c) const {
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
    std::memcpy(&low, words_ + node::childBase(w), sizeof low);
    std::memcpy(&high, words_ + node::childBase(w) + 4, sizeof high);
    const Lanes keep = Lanes{} + std::int32_t(no_targets_mask_),
                tag = Lanes{} + std::int32_t(node::kBitmapTag);
    const Lanes none =
        (((low & keep) == tag) & Lanes{1, 2, 4, 8}) | (((high & keep) == tag) & Lanes{16, 32, 64, 128});
    return ~std::uint32_t(none[0] | none[1] | none[2] | none[3]) & 0xFFu;
  }

  /** A node that holds the query: its children (or octants), except `skip`, nearest first, as the paper
   * orders them. */
  void searchAround(NodeWord w, std::size_t offset, unsigned level, const std::uint32_t base[3],
                    unsigned skip) {
    const bool bitmap = node::isBitmap(w);
    if (bitmap && policy_.wholeRegions()) {
      visitOctants(node::octantMask(w, target_) & ~(skip < 8 ? 1u << skip : 0u), level, base);
      return;
    }
    const unsigned sub = level - 1;
    const std::uint32_t mask = bitmap ? node::octantMask(w, target_) : childrenWithTargets(w);
    const std::size_t first = bitmap ? 0 : node::childBase(w);
    Child c[8];
    const int n = nearestFirst(base, sub, mask & ~(skip < 8 ? 1u << skip : 0u), c);
    const std::uint64_t rank = (bitmap && ranks_) ? ranks_[offset] : 0;
    for (int i = 0; i < n; ++i) {
      if (!policy_.worthVisiting(c[i].bound)) return;
      std::uint32_t lo[3];
      childCorner(base, sub, c[i].octant, lo);
      if (!policy_.mayImprove(c[i].bound, lo, sub)) continue;
      if (bitmap) {
        const std::uint32_t before = mask & ((1u << c[i].octant) - 1u);
        searchRegion(lo, sub, rank + node::cellsIn(node::popcount(before), sub));
      } else {
        searchWord(words_[first + c[i].octant], first + c[i].octant, sub, lo);
      }
    }
  }

  /** A policy that takes cubes whole finds each octant's best cell exactly: no bounds, no order needed. */
  void visitOctants(std::uint32_t mask, unsigned level, const std::uint32_t base[3]) {
    const unsigned sub = level - 1;
    for (unsigned o = 0; o < 8; ++o) {
      if (!((mask >> o) & 1u)) continue;
      std::uint32_t lo[3];
      childCorner(base, sub, o, lo);
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
  void searchWord(NodeWord w, std::size_t offset, unsigned level, const std::uint32_t base[3]) {
    std::uint32_t lo[3] = {base[0], base[1], base[2]};
    while (!node::isBitmap(w)) {
      const std::uint32_t children = childrenWithTargets(w);
      if (children & (children - 1)) {
        searchChildren(w, children, level, lo);
        return;
      }
      if (children == 0) return;
      const unsigned o = unsigned(__builtin_ctz(children)), sub = level - 1;
      Distance gap[3][2];
      policy_.childGaps(lo, sub, gap);
      const Distance bound = childBound(gap, o);
      childCorner(lo, sub, o, lo);
      if (!policy_.worthVisiting(bound) || !policy_.mayImprove(bound, lo, sub)) return;
      offset = node::childBase(w) + o;
      w = words_[offset];
      level = sub;
    }
    searchBitmap(w, offset, level, lo);
  }

  /** A bitmap word: its target octants are uniform cubes. */
  void searchBitmap(NodeWord w, std::size_t offset, unsigned level, const std::uint32_t base[3]) {
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
    Child c[8];
    const int n = nearestFirst(base, sub, mask, c);
    for (int i = 0; i < n; ++i) {
      if (!policy_.worthVisiting(c[i].bound)) return;
      std::uint32_t lo[3];
      childCorner(base, sub, c[i].octant, lo);
      if (!policy_.mayImprove(c[i].bound, lo, sub)) continue;
      const std::uint32_t before = mask & ((1u << c[i].octant) - 1u);
      searchRegion(lo, sub, rank + node::cellsIn(node::popcount(before), sub));
    }
  }

  /** The children of a reference word that may hold targets (`children`), nearest first. */
  void searchChildren(NodeWord w, std::uint32_t children, unsigned level, const std::uint32_t base[3]) {
    const std::size_t first = node::childBase(w);
    const unsigned sub = level - 1;
    Child c[8];
    const int n = nearestFirst(base, sub, children, c);
    for (int i = 0; i < n; ++i) {
      if (!policy_.worthVisiting(c[i].bound)) return;
      std::uint32_t lo[3];
      childCorner(base, sub, c[i].octant, lo);
      if (!policy_.mayImprove(c[i].bound, lo, sub)) continue;
      searchWord(words_[first + c[i].octant], first + c[i].octant, sub, lo);
    }
  }

  /** A uniform cube of target cells, split in its octants as far as the policy needs. */
  void searchRegion(const std::uint32_t lo[3], unsigned level, std::uint64_t rank) {
    if (level == 0) {
      policy_.visitCell(lo, rank);
      return;
    }
    if (policy_.wholeRegions()) {
      policy_.visitRegion(lo, level, rank);
      return;
    }
    const unsigned sub = level - 1;
    Child c[8];
    const int n = nearestFirst(lo, sub, 0xFFu, c);
    for (int i = 0; i < n; ++i) {
      if (!policy_.worthVisiting(c[i].bound)) return;
      std::uint32_t child[3];
      childCorner(lo, sub, c[i].octant, child);
      if (!policy_.mayImprove(c[i].bound, child, sub)) continue;
      searchRegion(child, sub, rank + node::cellsIn(c[i].octant, sub));
    }
  }

  const FastOctTree& tree_;
  const NodeWord* words_;
  CellState target_;
  NodeWord no_targets_mask_;  // a child word is a bitmap without targets iff (word & this) == kBitmapTag
  const std::uint64_t* ranks_;
  Policy& policy_;
};

}  // namespace detail

/** A cell found by NearestCellSearch, with its distance in cells (squared for the Euclidean metric). */
struct CellMatch {
  Key key;
  std::int64_t distance;
};

/**
 * Nearest-tree-neighbour queries at the cell level: the cells holding a state (Occupied by default) that
 * lie nearest to a query cell, in the Manhattan metric of the paper or the Euclidean one. Distances are
 * exact integers. Ties are broken by key: smaller x first, then y, then z.
 *
 * Keep one searcher per thread and ask it queries in spatial order: each query starts from the previous
 * one's path (LineBurstAccess). The tree must not change while a searcher uses it.
 */
class NearestCellSearch {
 public:
  static constexpr std::int64_t kUnbounded = std::numeric_limits<std::int64_t>::max();

  explicit NearestCellSearch(const FastOctTree& tree, Metric metric = Metric::Manhattan,
                             CellState target = CellState::Occupied);

  /** The nearest target cell within max_distance (inclusive); false if there is none. */
  bool nearest(const Key& query, CellMatch& match, std::int64_t max_distance = kUnbounded);
  /**
   * nearest() without the tie rule: a target cell at the least distance, not necessarily the smallest key.
   * Faster where only the distance counts, as in ψ: boxes that could only tie are not searched. A caller
   * that knows no target cell lies nearer than min_distance passes it, and the walk stops at the first
   * cell that near.
   */
  bool anyNearest(const Key& query, CellMatch& match, std::int64_t max_distance = kUnbounded,
                  std::int64_t min_distance = 0);
  /**
   * nearest() for many queries: matches[i] answers queries[i], with distance -1 where no target cell lies
   * within max_distance; returns how many were found. The answers are nearest()'s, in any order of the
   * queries. In the Manhattan metric the queries are taken a 16³ brick at a time, in Morton order, and the
   * target cells around a brick of several queries are dilated bit by bit, which settles every query
   * within 16 cells at once; only the rest are searched one by one. Runs over getNumberOfThreads() threads.
   */
  std::size_t nearest(const std::vector<Key>& queries, std::vector<CellMatch>& matches,
                      std::int64_t max_distance = kUnbounded);
  /** The k nearest target cells within max_distance, nearest first; returns how many. */
  std::size_t nearestK(const Key& query, std::size_t k, std::vector<CellMatch>& matches,
                       std::int64_t max_distance = kUnbounded);
  /** Every target cell within `radius` (inclusive), nearest first; returns how many. */
  std::size_t radius(const Key& query, std::int64_t radius, std::vector<CellMatch>& matches);

  const FastOctTree& tree() const { return tree_; }
  Metric metric() const { return metric_; }
  CellState target() const { return target_; }

  /**
   * Threads for the batch query: 1 (the default) runs it in the caller's thread, 0 takes every hardware
   * thread, and at most four per hardware thread are used. The answers do not depend on the count.
   */
  void setNumberOfThreads(unsigned threads) { threads_ = threads; }
  unsigned getNumberOfThreads() const { return threads_; }

 private:
  /** A cell found so far: ordered by distance, then by key (tree coordinates sort as keys do). */
  struct Candidate {
    std::int64_t distance;
    std::uint32_t u[3];
    bool operator<(const Candidate& o) const {
      if (distance != o.distance) return distance < o.distance;
      if (u[0] != o.u[0]) return u[0] < o.u[0];
      if (u[1] != o.u[1]) return u[1] < o.u[1];
      return u[2] < o.u[2];
    }
  };
  class Measure;
  class NearestOne;
  class NearestK;

  bool findNearest(const Key& query, CellMatch& match, std::int64_t max_distance, bool tie_rule,
                   std::int64_t floor);
  /** Fills heap_ with the best candidates, sorted; reuses its storage from query to query. */
  void search(const Key& query, std::size_t k, std::int64_t bound);
  std::size_t copyMatches(std::vector<CellMatch>& matches) const;

  const FastOctTree& tree_;
  Metric metric_;
  CellState target_;
  ConstAccessor accessor_;
  std::vector<Candidate> heap_;
  Key previous_;  // the last nearest cell: the next query's first candidate
  bool has_previous_ = false;
  unsigned threads_ = 1;
};

}  // namespace fot
}  // namespace pcl
