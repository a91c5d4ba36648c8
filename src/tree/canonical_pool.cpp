// The tree's canonical pool: what the .fot format stores, and its validation when read back.
#include <pcl_fot/tree/fast_oct_tree.h>

#include <cmath>
#include <cstring>
#include <string>

namespace pcl {
namespace fot {
namespace {

/**
 * Appends the subtree of the word w, at pool offset `at` (FastOctTree::wordValue), in pre-order, and the
 * values of its flagged words; references are renumbered to the blocks as they are appended.
 */
NodeWord appendSubtree(const FastOctTree& tree, std::size_t at, NodeWord w, FastOctTree::CanonicalPool& out) {
  if (node::isBitmap(w)) {
    if (node::hasValues(w))
      for (unsigned o = 0; o < 8; ++o) out.values.push_back(tree.wordValue(w, at, o));
    return w & ~node::kPaletteMask;  // palette indices follow the order of updates: the pool holds values
  }
  const std::size_t first = out.words.size();
  const std::uint32_t block = std::uint32_t(first / 8);
  out.words.resize(first + 8);
  for (unsigned o = 0; o < 8; ++o) {
    const std::size_t child_at = node::childOffset(w, o);
    const NodeWord child = appendSubtree(tree, child_at, tree.words()[child_at], out);
    out.words[first + o] = child;
  }
  return node::reference(block);
}

/** Checks a pool in pre-order and counts its cells; throws std::invalid_argument at the first flaw. */
class PoolCheck {
 public:
  PoolCheck(const std::vector<NodeWord>& words, const std::vector<float>& values, const SensorModel& model)
      : words_(words), values_(values), model_(model) {}

  void word(const NodeView& n) {
    if (n.isBitmap()) {
      bitmap(n);
      return;
    }
    if (n.level == 1) fail("a level-1 word refers to a block; leaves must be bitmaps");
    const std::uint32_t block = node::block(n.word);
    if (block != next_block_)
      fail("block " + std::to_string(block) + " is referenced where block " + std::to_string(next_block_) +
           " comes in pre-order");
    if (std::size_t(block) * 8 + 8 > words_.size()) fail("a reference points beyond the pool");
    ++next_block_;
    bool all_uniform = true;
    for (unsigned o = 0; o < 8; ++o) {
      const NodeView child = n.child(words_.data(), o);
      all_uniform = all_uniform && child.isUniform();
      word(child);
    }
    if (all_uniform) fail("block " + std::to_string(block) + " holds 8 uniform words, which fold into one");
  }

  std::uint32_t blocksSeen() const { return next_block_ - 1; }
  std::size_t valuesSeen() const { return next_value_; }
  std::uint64_t count(CellState s) const { return counts_[std::size_t(s)]; }

  [[noreturn]] static void fail(const std::string& what) {
    throw std::invalid_argument("pcl::fot::FastOctTree::fromCanonicalPool: " + what);
  }

 private:
  void bitmap(const NodeView& n) {
    const NodeWord w = n.word;
    const std::uint32_t states = w >> node::kStateShift;
    if ((w & 0xFFFCu) != 0) fail("a bitmap word has spare bits set");
    if ((states & (states >> 1) & 0x5555u) != 0) fail("a bitmap word holds an invalid state");
    if (node::hasValues(w)) leafValues(n);
    const std::uint32_t known =
        node::octantMask(w, CellState::Free) | node::octantMask(w, CellState::Occupied);
    if (!known) return;
    const unsigned sub = n.level - 1;
    if (sub > 20) fail("a uniform cube is too large to count");
    const std::uint32_t side = n.childSide();
    const std::uint32_t lo = tree_coord::fromKey(kMinKey), hi = tree_coord::fromKey(kMaxKey);
    for (unsigned o = 0; o < 8; ++o) {
      if (!((known >> o) & 1u)) continue;
      const TreeCoord c = n.corner.child(o, sub);
      for (unsigned a = 0; a < 3; ++a)
        if (c[a] < lo || std::uint64_t(c[a]) + side - 1 > hi) fail("known cells lie beyond the key range");
    }
    for (CellState s : {CellState::Free, CellState::Occupied}) {
      const std::uint64_t cells = std::uint64_t(node::popcount(node::octantMask(w, s))) << (3 * sub);
      std::uint64_t& count = counts_[std::size_t(s)];
      if (count + cells < count) fail("the cell count overflows");
      count += cells;
    }
  }

  /**
   * A flagged word's 8 values: NaN where the state is unknown, else finite and thresholded to the state,
   * and one value in every known octant above the leaves.
   */
  void leafValues(const NodeView& n) {
    if (values_.size() - next_value_ < 8) fail("the values end before the last flagged leaf");
    bool settled = true;
    for (unsigned o = 0; o < 8; ++o) {
      const float v = values_[next_value_ + o];
      const CellState s = node::state(n.word, o);
      if (std::isnan(v) != (s == CellState::Unknown))
        fail("a flagged leaf's value and state disagree on whether a cell is known");
      if (s == CellState::Unknown) continue;
      if (!std::isfinite(v)) fail("a log-odds is infinite");
      if ((model_.occupied(v) ? CellState::Occupied : CellState::Free) != s)
        fail("a flagged leaf's state is not its value thresholded");
      settled = settled && model_.settled(v);
      if (n.level > 1 && std::memcmp(&v, &values_[next_value_ + __builtin_ctz(known(n.word))], sizeof v) != 0)
        fail("a flagged word above the leaves holds more than one value");
    }
    if (settled) fail("a flagged leaf has no cell between the clamps");
    next_value_ += 8;
  }

  static std::uint32_t known(NodeWord w) { return ~node::octantMask(w, CellState::Unknown) & 0xFFu; }

  const std::vector<NodeWord>& words_;
  const std::vector<float>& values_;
  const SensorModel& model_;
  std::size_t next_value_ = 0;
  std::uint32_t next_block_ = 1;
  std::uint64_t counts_[3] = {0, 0, 0};
};

/** True if the root has two or more known octants (or children), or is a leaf: the smallest cube. */
bool minimalRoot(const std::vector<NodeWord>& words, NodeWord root, unsigned level) {
  if (level == 1) return true;
  unsigned known = 0;
  for (unsigned o = 0; o < 8; ++o)
    known += NodeView::childWord(words.data(), root, o) != node::uniform(CellState::Unknown);
  return known != 1;
}

}  // namespace

FastOctTree::CanonicalPool FastOctTree::canonicalPool() const {
  CanonicalPool pool;
  pool.model = model_;
  pool.words.assign(8, 0);
  if (empty()) {
    pool.words[0] = node::uniform(CellState::Unknown);
    return pool;
  }
  const NodeView root = contentRoot();
  pool.root_level = root.level;
  pool.root_base = root.corner;
  pool.words.reserve(8 * (1 + live_blocks_));
  pool.values.reserve(8 * value_leaves_);
  pool.words[0] = node::isBitmap(root.word) && !node::hasValues(root.word)
                      ? root.word
                      : appendSubtree(*this, offsetOf(root), root.word, pool);
  return pool;
}

FastOctTree FastOctTree::fromCanonicalPool(const CellGrid& grid, CanonicalPool pool, std::size_t max_bytes) {
  const unsigned level = pool.root_level;
  if (level < 1 || level > kMaxLevel)
    PoolCheck::fail("the root level " + std::to_string(level) + " is not in [1, 31]");
  if (pool.root_base.corner(level) != pool.root_base) PoolCheck::fail("the root is not aligned to its size");
  const std::vector<NodeWord>& words = pool.words;
  if (words.size() < 8 || words.size() % 8 != 0) PoolCheck::fail("the pool is not made of whole blocks");
  if (words.size() / 8 - 1 > node::kMaxBlocks)
    PoolCheck::fail("the pool has more blocks than a reference can address");
  if (words.size() * sizeof(NodeWord) > max_bytes)
    throw MemoryLimitError("pcl::fot::FastOctTree::fromCanonicalPool: the pool needs " +
                           std::to_string(words.size() * sizeof(NodeWord)) + " bytes, beyond the cap of " +
                           std::to_string(max_bytes));
  for (unsigned i = 1; i < 8; ++i)
    if (words[i] != 0) PoolCheck::fail("block 0 must hold the root word and seven zero words");
  const NodeWord root = words[0];
  // A reference's block must exist before the walk follows it, and a root reference is checked as any other.
  if (pool.values.size() / 8 > words.size() || pool.values.size() % 8 != 0)
    PoolCheck::fail("the values are not whole leaves of 8");
  if ((words.size() + pool.values.size()) * sizeof(float) > max_bytes)
    throw MemoryLimitError("pcl::fot::FastOctTree::fromCanonicalPool: the values need " +
                           std::to_string(pool.values.size() * sizeof(float)) +
                           " bytes more, beyond the cap of " + std::to_string(max_bytes));
  PoolCheck check(words, pool.values, pool.model);
  check.word(NodeView{root, level, pool.root_base});
  if (check.blocksSeen() != words.size() / 8 - 1)
    PoolCheck::fail("the pool holds blocks that no word refers to");
  if (check.valuesSeen() != pool.values.size()) PoolCheck::fail("the pool holds values that no leaf has");
  if (root == node::uniform(CellState::Unknown) ? (level != 1 || pool.root_base != TreeCoord())
                                                : !minimalRoot(words, root, level))
    PoolCheck::fail("the root is not the smallest cube holding the known cells");

  FastOctTree tree(grid);
  tree.model_ = pool.model;
  tree.words_ = std::move(pool.words);
  tree.root_level_ = level;
  tree.base_ = pool.root_base;
  tree.installValues(std::move(pool.values));
  tree.live_blocks_ = tree.words_.size() / 8 - 1;
  tree.counts_[std::size_t(CellState::Free)] = check.count(CellState::Free);
  tree.counts_[std::size_t(CellState::Occupied)] = check.count(CellState::Occupied);
  // Files written before cubes of one value folded spell them out as leaves: fold them now.
  tree.foldSubtree(0);
  tree.compactPool();
  return tree;
}

}  // namespace fot
}  // namespace pcl
