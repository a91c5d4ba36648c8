// The canonical pool: the .fot layout of a tree, and the checks that guard reading it back.
#include <gtest/gtest.h>

#include <random>

#include <pcl_fot/tree/fast_oct_tree.h>

using namespace pcl::fot;

namespace {

FastOctTree randomTree(unsigned seed, int writes) {
  std::mt19937 rng(seed);
  FastOctTree t(0.05, 0.5, -0.25, 1.0);
  for (int i = 0; i < writes; ++i) {
    const Key k{std::int32_t(rng() % 40) - 20, std::int32_t(rng() % 40) - 20, std::int32_t(rng() % 12)};
    t.setCell(k, CellState(1 + rng() % 2));
  }
  t.setBox({-64, -64, -8}, {-33, -33, -1}, CellState::Free);  // collapsed regions at several levels
  t.setCell({100000, -3, 7}, CellState::Occupied);            // a deep, sparse branch
  return t;
}

FastOctTree rebuilt(const FastOctTree& t) {
  return FastOctTree::fromCanonicalPool(t.getGrid(), t.canonicalPool());
}

/** Expects fromCanonicalPool to refuse `pool` with a message containing `why`. */
void expectRefused(const FastOctTree::CanonicalPool& pool, const std::string& why) {
  try {
    FastOctTree::fromCanonicalPool(CellGrid(0.1), pool);
    ADD_FAILURE() << "accepted a pool that should fail with: " << why;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(CanonicalPool, RoundTripGivesTheSameTreeAndTheSamePool) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const FastOctTree t = randomTree(seed, 3000 * seed);
    const FastOctTree back = rebuilt(t);
    EXPECT_TRUE(back == t);
    EXPECT_EQ(back.getOccupiedCount(), t.getOccupiedCount());
    EXPECT_EQ(back.getFreeCount(), t.getFreeCount());
    EXPECT_EQ(back.canonicalPool().words, t.canonicalPool().words);
    EXPECT_EQ(back.getBlockCount(), t.getBlockCount());
    // The rebuilt tree is a normal tree: it takes writes and grows.
    FastOctTree grown = back;
    grown.setCell({-5000000, 1, 1}, CellState::Free);
    EXPECT_EQ(grown.getCell({-5000000, 1, 1}), CellState::Free);
    EXPECT_EQ(grown.getFreeCount(), t.getFreeCount() + 1);
  }
}

TEST(CanonicalPool, EqualTreesGiveEqualPoolsWhateverTheirHistory) {
  FastOctTree a(0.1), b(0.1);
  std::vector<Key> keys;
  std::mt19937 rng(3);
  for (int i = 0; i < 5000; ++i)
    keys.push_back({std::int32_t(rng() % 64) - 32, std::int32_t(rng() % 64), std::int32_t(rng() % 8)});
  for (const Key& k : keys) a.setCell(k, CellState::Occupied);
  b.setCell({1 << 20, 0, 0}, CellState::Free);  // a larger root, erased again below
  for (auto it = keys.rbegin(); it != keys.rend(); ++it) b.setCell(*it, CellState::Occupied);
  b.eraseCell({1 << 20, 0, 0});
  ASSERT_NE(a.getDepth(), b.getDepth());
  const auto pa = a.canonicalPool(), pb = b.canonicalPool();
  EXPECT_EQ(pa.words, pb.words);
  EXPECT_EQ(pa.root_level, pb.root_level);
  EXPECT_EQ(pa.root_base, pb.root_base);
  FastOctTree empty(0.1);
  EXPECT_TRUE(rebuilt(empty).empty());
  EXPECT_EQ(empty.canonicalPool().words.size(), 8u);
}

TEST(CanonicalPool, EveryFlawIsNamed) {
  FastOctTree t(0.1);
  for (int i = 0; i < 40; ++i) t.setCell({i, 2 * i % 7, i % 3}, CellState::Occupied);
  const auto good = t.canonicalPool();
  ASSERT_GT(good.words.size(), 24u);
  const std::size_t first_ref = [&] {
    for (std::size_t i = 8; i < good.words.size(); ++i)
      if (!node::isBitmap(good.words[i])) return i;
    return std::size_t(0);
  }();
  ASSERT_NE(first_ref, 0u);

  auto pool = good;
  pool.root_level = 0;
  expectRefused(pool, "root level");
  pool = good;
  pool.root_base[0] += 1;
  expectRefused(pool, "aligned");
  pool = good;
  pool.words.pop_back();
  expectRefused(pool, "whole blocks");
  pool = good;
  pool.words[3] = 7;
  expectRefused(pool, "seven zero words");
  pool = good;
  pool.words.insert(pool.words.end(), 8, node::uniform(CellState::Free));
  expectRefused(pool, "no word refers to");
  pool = good;
  pool.words[first_ref] = node::reference(1);  // back to the first block: a cycle
  expectRefused(pool, "pre-order");
  pool = good;
  pool.words[first_ref] = node::reference(std::uint32_t(pool.words.size() / 8 + 5));
  expectRefused(pool, "pre-order");
  pool = good;
  pool.words[8] = node::uniform(CellState::Occupied) | 0x10u;
  expectRefused(pool, "spare bits");
  pool = good;
  pool.words[8] = node::kBitmapTag | (3u << node::kStateShift);
  expectRefused(pool, "invalid state");
  // A block of uniform words left unfolded.
  pool = good;
  for (std::size_t i = pool.words.size() - 8; i < pool.words.size(); ++i)
    pool.words[i] = node::uniform(CellState::Free);
  expectRefused(pool, "fold");
  // A reference below level 2: the deepest block's words are leaves.
  pool = good;
  pool.words[pool.words.size() - 1] = node::reference(1);
  expectRefused(pool, "level-1");
  // A root one level higher than needed, with the real root as its only child.
  pool = good;
  {
    std::vector<NodeWord> words(16, 0);
    words[0] = node::reference(1);
    for (int o = 0; o < 8; ++o) words[8 + o] = node::uniform(CellState::Unknown);
    words[8] = good.words[0];
    for (std::size_t i = 8; i < good.words.size(); ++i)
      words.push_back(node::isBitmap(good.words[i]) ? good.words[i]
                                                    : node::reference(node::block(good.words[i]) + 1));
    words[8] = node::isBitmap(good.words[0]) ? good.words[0] : node::reference(2);
    pool.words = words;
    pool.root_level = good.root_level + 1;
    pool.root_base = pool.root_base.corner(pool.root_level);
    if (pool.root_base == good.root_base) expectRefused(pool, "smallest cube");
  }
  // Known cells beyond the key range: a full root at the top of the coordinate space.
  FastOctTree::CanonicalPool far;
  far.words.assign(8, 0);
  far.words[0] = node::uniform(CellState::Occupied);
  far.root_level = 2;
  far.root_base = {0, 0, 0};
  expectRefused(far, "key range");
  // A word above the leaves whose octants hold two values: it names one, the cubes' value.
  FastOctTree::CanonicalPool two;
  two.words.assign(8, 0);
  two.words[0] = node::uniform(CellState::Free) | node::kValueFlag;
  two.values.assign(8, -0.4f);
  two.values[5] = -0.8f;
  two.root_level = 3;
  two.root_base = TreeCoord(Key{0, 0, 0});
  expectRefused(two, "more than one value");
  two.values[5] = -0.4f;
  EXPECT_EQ(FastOctTree::fromCanonicalPool(CellGrid(0.1), two).getUnsettledCount(), 512u);
  // The pool cap.
  EXPECT_THROW(FastOctTree::fromCanonicalPool(CellGrid(0.1), good, 64), MemoryLimitError);
}
