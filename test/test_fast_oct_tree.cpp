#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <unordered_map>
#include <vector>

#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/fast_oct_tree.h>

using namespace pcl::fot;

namespace {

using Model = std::unordered_map<Key, CellState, KeyHash>;

void apply(Model& m, const Key& k, CellState s) {
  if (s == CellState::Unknown)
    m.erase(k);
  else
    m[k] = s;
}

/** Walks the pool: counts reachable blocks and checks that no block could have been collapsed. */
std::size_t checkCanonical(const FastOctTree& t, NodeWord w, unsigned level) {
  if (node::isBitmap(w)) {
    EXPECT_EQ(w & 0xFFFEu, 0u) << "flag bits must stay clear";
    return 0;
  }
  EXPECT_GE(level, 2u) << "level-1 words are always bitmaps";
  const std::size_t first = node::childBase(w);
  EXPECT_LT(first + 7, t.poolWords());
  bool all_uniform = true;
  std::size_t blocks = 1;
  for (unsigned o = 0; o < 8; ++o) {
    const NodeWord c = t.words()[first + o];
    all_uniform = all_uniform && node::isUniform(c);
    blocks += checkCanonical(t, c, level - 1);
  }
  EXPECT_FALSE(all_uniform) << "a block of uniform words must have been collapsed";
  return blocks;
}

void checkAgainstModel(const FastOctTree& t, const Model& m) {
  std::uint64_t occ = 0, fr = 0;
  for (const auto& kv : m) (kv.second == CellState::Occupied ? occ : fr)++;
  ASSERT_EQ(t.getOccupiedCount(), occ);
  ASSERT_EQ(t.getFreeCount(), fr);
  std::size_t seen = 0;
  for (CellState s : {CellState::Occupied, CellState::Free}) {
    t.forEachCell(s, [&](const Key& k) {
      const auto it = m.find(k);
      ASSERT_TRUE(it != m.end()) << "tree holds " << toString(k) << " which the model lacks";
      ASSERT_EQ(it->second, s) << toString(k);
      ++seen;
    });
  }
  ASSERT_EQ(seen, m.size());
  for (const auto& kv : m) ASSERT_EQ(t.getCell(kv.first), kv.second) << toString(kv.first);
  EXPECT_EQ(checkCanonical(t, t.root().word, t.getDepth()), t.getBlockCount());
  EXPECT_EQ(t.getNodeCount(), 1 + 8 * t.getBlockCount());
}

/** A random workload that clusters writes so that blocks fill up, collapse, and expand again. */
struct Workload {
  explicit Workload(unsigned seed) : rng(seed) {
    const std::int32_t far = 1 << 27;
    for (std::int32_t sx : {-1, 0, 1})
      for (std::int32_t sy : {-1, 0, 1})
        for (std::int32_t sz : {-1, 0, 1}) centres.push_back(Key{sx * far + 3, sy * far - 5, sz * far + 7});
    centres.push_back(Key{0, 0, 0});
    centres.push_back(Key{kMaxKey - 7, kMinKey, kMaxKey - 7});
    centres.push_back(Key{kMinKey, kMaxKey - 7, 1000});
  }

  struct Op {
    enum Kind { Get, Set } kind;
    Key key;
    CellState state;
  };

  Op next() {
    // Mostly stay near one centre at a time; sometimes hop, which forces growth and deep restarts.
    if (rng() % 4096 == 0) centre = rng() % centres.size();
    if (rng() % 512 == 0) phase = CellState(rng() % 3);
    const Key& c = centres[centre];
    const std::int32_t span = (rng() % 8 == 0) ? 16 : 4;
    Key k{c.x + std::int32_t(rng() % span), c.y + std::int32_t(rng() % span),
          c.z + std::int32_t(rng() % span)};
    k.x = std::min(k.x, kMaxKey);
    k.y = std::min(k.y, kMaxKey);
    k.z = std::min(k.z, kMaxKey);
    if (rng() % 3 == 0) return Op{Op::Get, k, CellState::Unknown};
    const CellState s = (rng() % 8 == 0) ? CellState(rng() % 3) : phase;
    return Op{Op::Set, k, s};
  }

  std::mt19937 rng;
  std::vector<Key> centres;
  std::size_t centre = 0;
  CellState phase = CellState::Occupied;
};

}  // namespace

TEST(NodeWord, EncodingIsOneWordWithTagBit) {
  static_assert(sizeof(NodeWord) == 4, "");
  EXPECT_TRUE(node::isBitmap(node::uniform(CellState::Unknown)));
  EXPECT_FALSE(node::isBitmap(node::reference(5)));
  EXPECT_EQ(node::block(node::reference(123456)), 123456u);
  NodeWord w = node::uniform(CellState::Unknown);
  w = node::withState(w, 3, CellState::Occupied);
  w = node::withState(w, 6, CellState::Free);
  EXPECT_EQ(node::state(w, 3), CellState::Occupied);
  EXPECT_EQ(node::state(w, 6), CellState::Free);
  EXPECT_EQ(node::state(w, 0), CellState::Unknown);
  EXPECT_EQ(node::octantMask(w, CellState::Occupied), 1u << 3);
  EXPECT_EQ(node::octantMask(w, CellState::Free), 1u << 6);
  EXPECT_EQ(node::octantMask(w, CellState::Unknown), 0xFFu & ~((1u << 3) | (1u << 6)));
  EXPECT_FALSE(node::isUniform(w));
  for (CellState s : {CellState::Unknown, CellState::Free, CellState::Occupied}) {
    EXPECT_TRUE(node::isUniform(node::uniform(s)));
    EXPECT_EQ(node::uniformState(node::uniform(s)), s);
  }
  // Every bitmap: holds() agrees with the octant mask.
  for (std::uint32_t code = 0; code < 6561; ++code) {  // 3^8 assignments of states to octants
    NodeWord b = node::uniform(CellState::Unknown);
    for (unsigned o = 0, c = code; o < 8; ++o, c /= 3) b = node::withState(b, o, CellState(c % 3));
    for (CellState s : {CellState::Unknown, CellState::Free, CellState::Occupied})
      ASSERT_EQ(node::holds(b, s), node::octantMask(b, s) != 0) << std::hex << b;
  }
}

TEST(FastOctTree, RejectsBadResolution) {
  EXPECT_THROW(FastOctTree(0.0), std::invalid_argument);
  EXPECT_THROW(FastOctTree(-0.1), std::invalid_argument);
  EXPECT_THROW(FastOctTree{std::numeric_limits<double>::quiet_NaN()}, std::invalid_argument);
  EXPECT_THROW(FastOctTree{std::numeric_limits<double>::infinity()}, std::invalid_argument);
  EXPECT_THROW(FastOctTree(0.1, std::nan("")), std::invalid_argument);
  // Every cell centre of the key range must be a float, as PCL's points are.
  EXPECT_THROW(FastOctTree(1e30), std::invalid_argument);
  EXPECT_THROW(FastOctTree(0.05, 0.0, -1e39), std::invalid_argument);
  EXPECT_NO_THROW(FastOctTree(1e29));
  EXPECT_NO_THROW(FastOctTree(0.05, 512768.0, 5403699.0, 350.0));  // UTM
}

TEST(FastOctTree, RandomizedAgainstHashModel) {
  FastOctTree tree(0.05);
  Model model;
  Workload work(20240611);
  Accessor writer_a(tree), writer_b(tree);
  ConstAccessor reader(tree);
  const std::size_t kOps = 3'000'000;
  std::size_t collapses_seen = 0;
  for (std::size_t i = 0; i < kOps; ++i) {
    const auto op = work.next();
    if (op.kind == Workload::Op::Get) {
      const auto it = model.find(op.key);
      const CellState expect = it == model.end() ? CellState::Unknown : it->second;
      ASSERT_EQ(reader.getCell(op.key), expect) << "op " << i << " key " << toString(op.key);
    } else {
      const std::size_t blocks_before = tree.getBlockCount();
      ((i & 1) ? writer_a : writer_b).setCell(op.key, op.state);
      apply(model, op.key, op.state);
      collapses_seen += tree.getBlockCount() < blocks_before;
    }
    if (i % 500'000 == 0) checkAgainstModel(tree, model);
  }
  checkAgainstModel(tree, model);
  EXPECT_GT(collapses_seen, 1000u) << "the workload must exercise collapse";
  EXPECT_GE(tree.getDepth(), 28u) << "the workload must grow the root in every direction";
}

TEST(FastOctTree, LineBurstOnAndOffGiveIdenticalTrees) {
  FastOctTree on(0.05), off(0.05), direct(0.05);
  Accessor a_on(on, true), a_off(off, false);
  Workload work(7);
  for (std::size_t i = 0; i < 1'000'000; ++i) {
    const auto op = work.next();
    if (op.kind == Workload::Op::Get) {
      ASSERT_EQ(a_on.getCell(op.key), a_off.getCell(op.key));
      continue;
    }
    a_on.setCell(op.key, op.state);
    a_off.setCell(op.key, op.state);
    direct.setCell(op.key, op.state);
  }
  EXPECT_TRUE(on == off);
  EXPECT_TRUE(on == direct);
  // The same writes allocate the same blocks in the same order: the pools match word for word.
  ASSERT_EQ(on.poolWords(), off.poolWords());
  EXPECT_TRUE(std::equal(on.words(), on.words() + on.poolWords(), off.words()));
}

TEST(FastOctTree, AccessorSurvivesChangesMadeElsewhere) {
  FastOctTree tree(0.1);
  Accessor a(tree), b(tree);
  a.setCell({0, 0, 0}, CellState::Occupied);
  EXPECT_EQ(a.getCell({1, 0, 0}), CellState::Unknown);
  // b fills the 2x2x2 cube, which collapses the leaf a cached.
  for (int o = 0; o < 8; ++o) b.setCell({o & 1, (o >> 1) & 1, (o >> 2) & 1}, CellState::Occupied);
  EXPECT_EQ(a.getCell({1, 1, 1}), CellState::Occupied);
  // b grows the root far away; a's cached path is now one of many levels below.
  b.setCell({-100000, 5, 5}, CellState::Free);
  EXPECT_EQ(a.getCell({1, 0, 1}), CellState::Occupied);
  EXPECT_EQ(a.getCell({-100000, 5, 5}), CellState::Free);
  // a expands the collapsed cube again; b must see it.
  a.setCell({1, 1, 0}, CellState::Free);
  EXPECT_EQ(b.getCell({1, 1, 0}), CellState::Free);
  EXPECT_EQ(b.getCell({0, 1, 0}), CellState::Occupied);
  tree.clear();
  EXPECT_EQ(a.getCell({0, 0, 0}), CellState::Unknown);
  EXPECT_EQ(b.getCell({-100000, 5, 5}), CellState::Unknown);
}

TEST(FastOctTree, CollapseFoldsUniformCubesAndWritesExpandThem) {
  FastOctTree tree(0.1);
  // An aligned 8x8x8 cube in tree coordinates: three levels of blocks fold into one octant.
  const std::uint32_t base = tree_coord::fromKey(0) & ~0xFFu;  // aligned in tree coordinates
  const Key corner{tree_coord::toKey(base), tree_coord::toKey(base), tree_coord::toKey(base)};
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        tree.setCell({corner.x + x, corner.y + y, corner.z + z}, CellState::Occupied);
  EXPECT_EQ(tree.getOccupiedCount(), 512u);
  std::vector<Region> regions;
  tree.forEachRegion([&](const Region& r) { regions.push_back(r); });
  ASSERT_EQ(regions.size(), 1u);
  EXPECT_EQ(regions[0].level, 3u);
  EXPECT_EQ(regions[0].min_key, corner);
  EXPECT_EQ(tree.getBlockCount(), 0u) << "the whole map is one bitmap word at the root";

  tree.setCell({corner.x + 5, corner.y + 2, corner.z + 7}, CellState::Free);
  EXPECT_EQ(tree.getDepth(), 3u);
  EXPECT_EQ(tree.getBlockCount(), 2u) << "one write re-expands one block per level below the root";
  EXPECT_EQ(tree.getCell({corner.x + 5, corner.y + 2, corner.z + 7}), CellState::Free);
  EXPECT_EQ(tree.getCell({corner.x + 4, corner.y + 2, corner.z + 7}), CellState::Occupied);
  tree.setCell({corner.x + 5, corner.y + 2, corner.z + 7}, CellState::Occupied);
  EXPECT_EQ(tree.getBlockCount(), 0u) << "restoring the cell collapses everything again";
}

TEST(FastOctTree, DepthFollowsTheExtent) {
  // Levels 1 to 16 are OctoMap's: key 0 is a boundary of each, and the level-16 node is OctoMap's root.
  FastOctTree tree(0.01);
  tree.setCell({0, 0, 0}, CellState::Occupied);
  tree.setCell({1023, 1023, 1023}, CellState::Occupied);
  EXPECT_EQ(tree.getDepth(), 10u) << "an aligned map of 1024 cells a side needs 10 levels";
  FastOctTree centred(0.01);
  centred.setCell({-512, -512, -512}, CellState::Occupied);
  centred.setCell({511, 511, 511}, CellState::Occupied);
  EXPECT_EQ(centred.getDepth(), 16u) << "one around key 0 is OctoMap's root";
  FastOctTree small(0.01);
  small.setCell({-3, 2, 1}, CellState::Occupied);
  small.setCell({3, -2, -1}, CellState::Occupied);
  EXPECT_EQ(small.getDepth(), 16u);
  // Beyond OctoMap's cube the levels alternate sides again: about log2(extent) + 1.
  FastOctTree large(0.01);
  large.setCell({-200000, -200000, -200000}, CellState::Occupied);
  large.setCell({200000, 200000, 200000}, CellState::Occupied);
  EXPECT_LE(large.getDepth(), 21u);
}

TEST(FastOctTree, KeyRangeLimits) {
  FastOctTree tree(0.01);
  const Key extremes[] = {{kMinKey, kMinKey, kMinKey}, {kMaxKey, kMaxKey, kMaxKey}, {kMinKey, kMaxKey, 0}};
  for (const Key& k : extremes) tree.setCell(k, CellState::Occupied);
  for (const Key& k : extremes) EXPECT_EQ(tree.getCell(k), CellState::Occupied);
  EXPECT_LE(tree.getDepth(), kMaxLevel);
  const FastOctTree before = tree;
  EXPECT_THROW(tree.setCell({kMaxKey + 1, 0, 0}, CellState::Occupied), std::out_of_range);
  EXPECT_THROW(tree.setCell({0, kMinKey - 1, 0}, CellState::Free), std::out_of_range);
  EXPECT_THROW(tree.setCell({0, 0, std::numeric_limits<std::int32_t>::max()}, CellState::Occupied),
               std::out_of_range);
  EXPECT_TRUE(tree == before) << "a rejected write changes nothing";
  EXPECT_EQ(tree.getCell({kMaxKey + 1, 0, 0}), CellState::Unknown);
  // Points: 2^29 cells of 1 cm is about 5368 km.
  EXPECT_THROW(tree.setCellAtPoint(6.0e6, 0, 0, CellState::Occupied), std::out_of_range);
  EXPECT_EQ(tree.getCellAtPoint(6.0e6, 0, 0), CellState::Unknown);
  EXPECT_TRUE(tree == before);
}

TEST(FastOctTree, NonFinitePointsAreSkippedAndCounted) {
  FastOctTree tree(0.05);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  // Four floats per point, like pcl::PointXYZ.
  const std::vector<float> pts = {0.1f, 0.2f, 0.3f, 1, nan,   0, 0, 1, 0,     inf,   0,     1,
                                  -inf, 0,    0,    1, 1e30f, 0, 0, 1, 0.12f, 0.21f, 0.33f, 1};
  const InsertStats st = tree.insertPoints(pts.data(), 6, 4 * sizeof(float));
  EXPECT_EQ(st.inserted, 2u);
  EXPECT_EQ(st.non_finite, 3u);
  EXPECT_EQ(st.out_of_range, 1u);
  EXPECT_EQ(tree.getOccupiedCount(), 1u) << "both valid points fall into one 5 cm cell";
  EXPECT_THROW(tree.setCellAtPoint(nan, 0, 0, CellState::Occupied), std::invalid_argument);
  EXPECT_THROW(tree.getCellAtPoint(0, inf, 0), std::invalid_argument);
  EXPECT_EQ(tree.getOccupiedCount(), 1u);
}

TEST(FastOctTree, PointsMapToCellsOfTheGrid) {
  FastOctTree tree(0.1, 1.0, -2.0, 0.5);
  tree.setCellAtPoint(1.05, -1.95, 0.55, CellState::Occupied);
  EXPECT_EQ(tree.getCell({0, 0, 0}), CellState::Occupied);
  tree.setCellAtPoint(0.95, -2.05, 0.45, CellState::Free);
  EXPECT_EQ(tree.getCell({-1, -1, -1}), CellState::Free);
  double x, y, z;
  tree.getGrid().keyToCenter({-1, -1, -1}, x, y, z);
  EXPECT_NEAR(x, 0.95, 1e-12);
  EXPECT_NEAR(y, -2.05, 1e-12);
  EXPECT_NEAR(z, 0.45, 1e-12);
  tree.eraseCellAtPoint(0.95, -2.05, 0.45);
  EXPECT_EQ(tree.getCell({-1, -1, -1}), CellState::Unknown);
  EXPECT_EQ(tree.getFreeCount(), 0u);
}

TEST(FastOctTree, BatchKeysSkipInvalidOnes) {
  FastOctTree tree(0.1);
  const std::vector<Key> keys = {{1, 2, 3}, {kMaxKey + 1, 0, 0}, {4, 5, 6}, {1, 2, 3}};
  const InsertStats st = tree.insertKeys(keys.data(), keys.size(), CellState::Free);
  EXPECT_EQ(st.inserted, 3u);
  EXPECT_EQ(st.out_of_range, 1u);
  EXPECT_EQ(tree.getFreeCount(), 2u);
}

TEST(FastOctTree, IterationIsInMortonOrderOfTreeCoordinates) {
  FastOctTree tree(0.1);
  std::mt19937 rng(3);
  Model model;
  for (int i = 0; i < 20000; ++i) {
    const Key k{std::int32_t(rng() % 200) - 100, std::int32_t(rng() % 200) - 100, std::int32_t(rng() % 50)};
    const CellState s = (rng() % 2) ? CellState::Occupied : CellState::Free;
    tree.setCell(k, s);
    model[k] = s;
  }
  auto morton = [](const Key& k) {
    const std::uint32_t u[3] = {tree_coord::fromKey(k.x), tree_coord::fromKey(k.y), tree_coord::fromKey(k.z)};
    unsigned __int128 m = 0;
    for (int b = 31; b >= 0; --b)
      for (int a = 2; a >= 0; --a) m = (m << 1) | ((u[a] >> b) & 1u);
    return m;
  };
  unsigned __int128 last = 0;
  bool first = true;
  std::size_t cells = 0;
  tree.forEachRegion([&](const Region& r) {
    const auto m = morton(r.min_key);
    if (!first) {
      EXPECT_GT(m, last);
    }
    first = false;
    last = m;
    cells += std::size_t(1) << (3 * r.level);
  });
  EXPECT_EQ(cells, model.size());
  std::vector<Key> occupied;
  tree.forEachCell(CellState::Occupied, [&](const Key& k) { occupied.push_back(k); });
  EXPECT_TRUE(std::is_sorted(occupied.begin(), occupied.end(),
                             [&](const Key& a, const Key& b) { return morton(a) < morton(b); }));
  EXPECT_EQ(occupied.size(), tree.getOccupiedCount());
  EXPECT_THROW(tree.forEachCell(CellState::Unknown, [](const Key&) {}), std::invalid_argument);
}

TEST(FastOctTree, MemoryAccountingIsExact) {
  FastOctTree tree(0.02);
  EXPECT_EQ(tree.getMemoryBytes(), sizeof(FastOctTree) + 8 * sizeof(NodeWord));
  EXPECT_EQ(tree.getBlockCount(), 0u);
  std::mt19937 rng(11);
  for (int i = 0; i < 50000; ++i)
    tree.setCell({std::int32_t(rng() % 500), std::int32_t(rng() % 500), std::int32_t(rng() % 500)},
                 CellState::Occupied);
  EXPECT_EQ(checkCanonical(tree, tree.root().word, tree.getDepth()), tree.getBlockCount());
  EXPECT_GE(tree.getMemoryBytes(), sizeof(FastOctTree) + (1 + tree.getBlockCount()) * 32);
  EXPECT_LE(tree.getMemoryBytes(), sizeof(FastOctTree) + 2 * (1 + tree.getBlockCount()) * 32 + 64);
  tree.clear();
  EXPECT_EQ(tree.getMemoryBytes(), sizeof(FastOctTree) + 8 * sizeof(NodeWord));
  EXPECT_EQ(tree.getOccupiedCount(), 0u);
  EXPECT_TRUE(tree.empty());
}

TEST(FastOctTree, FreedBlocksAreReused) {
  FastOctTree tree(0.1);
  for (int round = 0; round < 5; ++round) {
    for (int i = 0; i < 64; ++i) tree.setCell({i * 3, -i * 5, i * 7}, CellState::Occupied);
    for (int i = 0; i < 64; ++i) tree.eraseCell({i * 3, -i * 5, i * 7});
  }
  const std::size_t pool = tree.poolWords();
  for (int i = 0; i < 64; ++i) tree.setCell({i * 3, -i * 5, i * 7}, CellState::Occupied);
  EXPECT_EQ(tree.poolWords(), pool) << "the free list supplies every block of a repeated workload";
  for (int i = 0; i < 64; ++i) tree.eraseCell({i * 3, -i * 5, i * 7});
  EXPECT_EQ(tree.getBlockCount(), 0u);
  EXPECT_TRUE(tree.empty());
}

TEST(FastOctTree, EqualityIsAboutCellsNotHistory) {
  FastOctTree a(0.1), b(0.1);
  std::vector<Key> keys;
  for (int i = 0; i < 3000; ++i) keys.push_back({(i * 37) % 101 - 50, (i * 53) % 97 - 48, (i * 11) % 89});
  for (const Key& k : keys) a.setCell(k, CellState::Occupied);
  std::reverse(keys.begin(), keys.end());
  b.setCell({1 << 25, -(1 << 25), 0}, CellState::Free);  // grows b far beyond a
  for (const Key& k : keys) b.setCell(k, CellState::Occupied);
  EXPECT_FALSE(a == b);
  b.eraseCell({1 << 25, -(1 << 25), 0});
  EXPECT_GT(b.getDepth(), a.getDepth());
  EXPECT_TRUE(a == b);
  b.setCell(keys[5], CellState::Free);
  EXPECT_FALSE(a == b);
  b.setCell(keys[5], CellState::Occupied);
  EXPECT_TRUE(a == b);
  EXPECT_FALSE(a == FastOctTree(0.2)) << "different grids";
  FastOctTree c(0.1, 0.05);
  EXPECT_FALSE(FastOctTree(0.1) == c);
  EXPECT_TRUE(FastOctTree(0.1) == FastOctTree(0.1));
}

TEST(FastOctTree, EqualityWithFullCubesAtDifferentRootLevels) {
  // a holds one full 4x4x4 cube as its root word; b holds the same cube one level deeper in its tree.
  FastOctTree a(0.1), b(0.1);
  const std::uint32_t base = tree_coord::fromKey(0) & ~0xFFu;
  b.setCell({tree_coord::toKey(base + 100), 0, 0}, CellState::Occupied);
  for (int i = 0; i < 64; ++i) {
    const Key k{tree_coord::toKey(base + (i & 3)), tree_coord::toKey(base + ((i >> 2) & 3)),
                tree_coord::toKey(base + (i >> 4))};
    a.setCell(k, CellState::Occupied);
    b.setCell(k, CellState::Occupied);
  }
  b.eraseCell({tree_coord::toKey(base + 100), 0, 0});
  EXPECT_TRUE(a == b);
}

TEST(FastOctTree, MemoryCapRefusesWritesAndKeepsTheTree) {
  FastOctTree tree(0.1);
  tree.setMaxMemoryBytes(4096);
  std::size_t refused = 0;
  for (int i = 0; i < 2000; ++i) {
    const Key k{i * 17, i * 31, -i * 13};
    const FastOctTree before = tree;
    try {
      tree.setCell(k, CellState::Occupied);
    } catch (const MemoryLimitError&) {
      ++refused;
      EXPECT_TRUE(tree == before);
    }
  }
  EXPECT_GT(refused, 0u);
  EXPECT_LE(tree.poolWords() * sizeof(NodeWord), 4096u);
}

TEST(FastOctTree, AWriteRefusedBeyondTheRootLeavesThePoolAsItWas) {
  // A write beyond the root first grows it, then builds the path down to the cell or cube. Both must fit
  // the cap before either starts: a refused write used to leave the root grown by up to 30 levels.
  struct Write {
    Key lo, hi;
    bool whole;  // one cell or one aligned cube, refused whole; a box keeps the cubes written before
  };
  const std::int32_t aligned = tree_coord::toKey(tree_coord::fromKey(4096) & ~7u),
                     cube = tree_coord::toKey(tree_coord::fromKey(0) & ~15u);
  const Write writes[] = {{{-70, 5, 1000}, {-70, 5, 1000}, true},
                          {{kMaxKey, kMinKey, 0}, {kMaxKey, kMinKey, 0}, true},
                          {{aligned, 0, 0}, {aligned, 0, 0}, true},
                          {{aligned, aligned, aligned}, {aligned + 7, aligned + 7, aligned + 7}, true},
                          {{-3000, 900, 17}, {-2990, 911, 17}, false}};
  for (bool uniform_root : {false, true})
    for (const Write& w : writes)
      for (std::size_t cap = 64; cap <= 2048; cap += 32) {
        FastOctTree tree(0.1);
        if (uniform_root)  // an aligned cube: growth folds it into its parent's bitmap without a block
          tree.setBox(Key{cube, cube, cube}, Key{cube + 15, cube + 15, cube + 15}, CellState::Free);
        else
          tree.setCell({3, 2, 1}, CellState::Occupied);
        ASSERT_EQ(uniform_root, node::isUniform(tree.root().word));
        FastOctTree unlimited = tree;
        unlimited.setBox(w.lo, w.hi, CellState::Occupied);
        tree.setMaxMemoryBytes(std::max(cap, tree.poolWords() * sizeof(NodeWord)));
        const std::vector<NodeWord> pool(tree.words(), tree.words() + tree.poolWords());
        const unsigned depth = tree.getDepth();
        try {
          if (w.lo == w.hi)
            Accessor(tree).setCell(w.lo, CellState::Occupied);
          else
            tree.setBox(w.lo, w.hi, CellState::Occupied);
          EXPECT_TRUE(tree == unlimited) << "cap " << cap;
        } catch (const MemoryLimitError&) {
          EXPECT_GT(unlimited.poolWords() * sizeof(NodeWord), tree.getMaxMemoryBytes())
              << "refused, though the write fits in " << tree.getMaxMemoryBytes() << " bytes";
          if (!w.whole) continue;
          EXPECT_EQ(tree.getDepth(), depth) << "cap " << cap;
          ASSERT_EQ(tree.poolWords(), pool.size()) << "cap " << cap;
          EXPECT_TRUE(std::equal(pool.begin(), pool.end(), tree.words())) << "cap " << cap;
        }
      }
}

TEST(FastOctTree, RegionsInABoxAreThoseThatOverlapIt) {
  FastOctTree tree(0.1);
  std::mt19937 rng(31);
  for (int i = 0; i < 30000; ++i)
    tree.setCell({std::int32_t(rng() % 64) - 32, std::int32_t(rng() % 64) - 32, std::int32_t(rng() % 16)},
                 (rng() % 3) ? CellState::Occupied : CellState::Free);
  for (int trial = 0; trial < 50; ++trial) {
    Key lo{std::int32_t(rng() % 80) - 40, std::int32_t(rng() % 80) - 40, std::int32_t(rng() % 20) - 2};
    const Key hi{lo.x + std::int32_t(rng() % 20), lo.y + std::int32_t(rng() % 20),
                 lo.z + std::int32_t(rng() % 6)};
    std::uint64_t expected = 0;
    for (std::int32_t z = lo.z; z <= hi.z; ++z)
      for (std::int32_t y = lo.y; y <= hi.y; ++y)
        for (std::int32_t x = lo.x; x <= hi.x; ++x) expected += tree.getCell({x, y, z}) != CellState::Unknown;
    std::uint64_t counted = 0;
    tree.forEachRegionInBox(lo, hi, [&](const Region& r) {
      const std::int64_t side = std::int64_t(1) << r.level;
      for (std::int64_t z = std::max<std::int64_t>(r.min_key.z, lo.z);
           z < std::min<std::int64_t>(r.min_key.z + side, hi.z + 1); ++z)
        for (std::int64_t y = std::max<std::int64_t>(r.min_key.y, lo.y);
             y < std::min<std::int64_t>(r.min_key.y + side, hi.y + 1); ++y)
          counted += std::max<std::int64_t>(0, std::min<std::int64_t>(r.min_key.x + side, hi.x + 1) -
                                                   std::max<std::int64_t>(r.min_key.x, lo.x));
    });
    ASSERT_EQ(counted, expected) << "box " << toString(lo) << " .. " << toString(hi);
    bool stopped_early = true;
    int visits = 0;
    tree.forEachRegionInBox(lo, hi, [&](const Region&) { return ++visits < 1; });
    stopped_early = visits <= 1;
    EXPECT_TRUE(stopped_early) << "a visitor returning false stops the walk";
  }
}

TEST(FastOctTree, BoxesAgainstHashModel) {
  std::mt19937 rng(47);
  FastOctTree tree(0.1);
  Model model;
  // Near the origin, and at the edges of the key range, where the root grows to its full height.
  const Key centres[] = {{0, 0, 0},
                         {-37, 12, 5},
                         {kMaxKey - 30, kMinKey, 3},
                         {kMinKey, kMinKey, kMinKey},
                         {kMaxKey - 30, kMaxKey - 30, kMaxKey - 30}};
  for (int i = 0; i < 3000; ++i) {
    const Key& c = centres[(i / 300) % 5];
    Key lo{c.x + std::int32_t(rng() % 24), c.y + std::int32_t(rng() % 24), c.z + std::int32_t(rng() % 24)};
    Key hi{lo.x + std::int32_t(rng() % 14), lo.y + std::int32_t(rng() % 14), lo.z + std::int32_t(rng() % 14)};
    hi = Key{std::min(hi.x, kMaxKey), std::min(hi.y, kMaxKey), std::min(hi.z, kMaxKey)};
    const CellState s = CellState(rng() % 3);
    if (rng() % 4 == 0) {  // single cells in between, through the accessor's path
      tree.setCell(lo, s);
      apply(model, lo, s);
    } else {
      tree.setBox(lo, hi, s);
      for (std::int32_t z = lo.z; z <= hi.z; ++z)
        for (std::int32_t y = lo.y; y <= hi.y; ++y)
          for (std::int32_t x = lo.x; x <= hi.x; ++x) apply(model, {x, y, z}, s);
    }
    if (i % 250 == 0) checkAgainstModel(tree, model);
  }
  checkAgainstModel(tree, model);
}

TEST(FastOctTree, ABoxOnAFreshTreeAnywhere) {
  // A fresh tree's first box may be a whole cube away from its root: the root must become that cube, not
  // grow to one corner and then re-anchor at the other (a 7-cell box at key 110 threw MemoryLimitError).
  for (std::int32_t at : {0, 1, 110, 112, -77, 4096, kMaxKey - 20, kMinKey})
    for (std::int32_t side = 1; side <= 12; ++side)
      for (CellState s : {CellState::Free, CellState::Occupied}) {
        FastOctTree boxed(0.1), celled(0.1);
        const Key lo{at, at, at}, hi{at + side - 1, at + side - 1, at + side - 1};
        ASSERT_NO_THROW(boxed.setBox(lo, hi, s)) << "at " << at << ", side " << side;
        for (std::int32_t z = lo.z; z <= hi.z; ++z)
          for (std::int32_t y = lo.y; y <= hi.y; ++y)
            for (std::int32_t x = lo.x; x <= hi.x; ++x) celled.setCell(Key{x, y, z}, s);
        ASSERT_TRUE(boxed == celled) << "at " << at << ", side " << side;
      }
}

TEST(FastOctTree, HugeBoxesCostTheirSurface) {
  FastOctTree tree(0.1);
  const Key lo{-200, -210, -190}, hi{311, 301, 321};  // 512³ cells, not aligned
  tree.setBox(lo, hi, CellState::Free);
  EXPECT_EQ(tree.getFreeCount(), std::uint64_t(512) * 512 * 512);
  // Inside, the box collapses; its faces need leaves: about a word per 2x2 patch of its 1.5 M surface cells.
  EXPECT_LT(tree.getNodeCount(), 1'000'000u) << "a word per maximal cube, not per cell";
  EXPECT_EQ(tree.getCell(lo), CellState::Free);
  EXPECT_EQ(tree.getCell(hi), CellState::Free);
  EXPECT_EQ(tree.getCell({hi.x + 1, 0, 0}), CellState::Unknown);
  tree.setBox({-10, -10, -10}, {10, 10, 10}, CellState::Occupied);
  EXPECT_EQ(tree.getOccupiedCount(), 21u * 21 * 21);
  EXPECT_EQ(tree.getFreeCount(), std::uint64_t(512) * 512 * 512 - 21 * 21 * 21);
  tree.setBox(lo, hi, CellState::Unknown);
  EXPECT_TRUE(tree.empty());
  EXPECT_EQ(tree.getBlockCount(), 0u);
  EXPECT_EQ(tree.getOccupiedCount() + tree.getFreeCount(), 0u);

  // Boxes beyond the root make it grow, whichever corner lies outside.
  tree.setCell({1, 2, 3}, CellState::Occupied);
  tree.setBox({-16, -16, -16}, {-1, -1, -1}, CellState::Free);
  tree.setBox({1000, 0, 0}, {1063, 63, 63}, CellState::Occupied);
  tree.setBox({-5000, -5000, -5000}, {-4999, -4999, -4999}, CellState::Free);
  EXPECT_EQ(tree.getOccupiedCount(), 1u + 64 * 64 * 64);
  EXPECT_EQ(tree.getFreeCount(), 16u * 16 * 16 + 8);
  EXPECT_EQ(tree.getCell({1063, 63, 63}), CellState::Occupied);
  tree.setBox({-5000, -5000, -5000}, {1063, 63, 63}, CellState::Unknown);
  EXPECT_TRUE(tree.empty());

  EXPECT_THROW(tree.setBox({0, 0, 0}, {-1, 0, 0}, CellState::Free), std::invalid_argument) << "empty box";
  EXPECT_THROW(tree.setBox({kMinKey, kMinKey, 0}, {kMaxKey, kMaxKey, 0}, CellState::Free),
               std::invalid_argument)
      << "2^60 cells";
  EXPECT_THROW(tree.setBox({0, 0, 0}, {kMaxKey + 1, 0, 0}, CellState::Free), std::out_of_range);
  EXPECT_TRUE(tree.empty());
}
