#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <vector>

#include <pcl_fot/dense/fast_occ_mesh.h>
#include <pcl_fot/tree/fast_oct_tree.h>

using namespace pcl::fot;

TEST(FastOccMesh, DefaultIsThePapers128MiBGrid) {
  FastOccMesh grid(CellGrid(0.01));
  EXPECT_EQ(grid.getSide(), 1024u);
  EXPECT_EQ(grid.getMinKey(), (Key{-512, -512, -512}));
  EXPECT_EQ(grid.getMemoryBytes(), sizeof(FastOccMesh) + (std::size_t(128) << 20));
  grid.setCell({0, 0, 0}, CellState::Occupied);
  EXPECT_FALSE(grid.hasFreePlane()) << "a binary map keeps one bit per cell";
  grid.setCell({1, 0, 0}, CellState::Free);
  EXPECT_TRUE(grid.hasFreePlane());
  EXPECT_EQ(grid.getMemoryBytes(), sizeof(FastOccMesh) + (std::size_t(256) << 20));
  EXPECT_EQ(grid.getCell({0, 0, 0}), CellState::Occupied) << "adding the free plane keeps the cells";
  EXPECT_EQ(grid.getCell({1, 0, 0}), CellState::Free);
}

TEST(FastOccMesh, RejectsBadGeometry) {
  EXPECT_THROW(FastOccMesh(CellGrid(0.1), 0), std::invalid_argument);
  EXPECT_THROW(FastOccMesh(CellGrid(0.1), 16, Key{kMaxKey - 4, 0, 0}), std::out_of_range);
  EXPECT_THROW(FastOccMesh(CellGrid(-1.0), 16), std::invalid_argument);
}

TEST(FastOccMesh, CellsOutsideTheCube) {
  FastOccMesh grid(CellGrid(0.1), 8, Key{10, 20, 30});
  EXPECT_TRUE(grid.contains({10, 20, 30}));
  EXPECT_TRUE(grid.contains({17, 27, 37}));
  EXPECT_FALSE(grid.contains({18, 20, 30}));
  EXPECT_FALSE(grid.contains({9, 20, 30}));
  EXPECT_EQ(grid.getCell({9, 20, 30}), CellState::Unknown);
  EXPECT_THROW(grid.setCell({9, 20, 30}, CellState::Occupied), std::out_of_range);
  const std::vector<Key> keys = {{10, 20, 30}, {100, 0, 0}, {11, 21, 31}};
  const InsertStats st = grid.insertKeys(keys.data(), keys.size());
  EXPECT_EQ(st.inserted, 2u);
  EXPECT_EQ(st.out_of_range, 1u);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> pts = {1.05f, 2.05f, 3.05f, nan, 0, 0, 50, 50, 50};
  const InsertStats ps = grid.insertPoints(pts.data(), 3, 3 * sizeof(float));
  EXPECT_EQ(ps.inserted, 1u);
  EXPECT_EQ(ps.non_finite, 1u);
  EXPECT_EQ(ps.out_of_range, 1u);
  EXPECT_EQ(grid.getOccupiedCount(), 2u);
}

TEST(FastOccMesh, SameCellsAsTheTreeUnderRandomWrites) {
  const CellGrid vg(0.05);
  FastOccMesh grid(vg, 64, Key{-20, -30, -40});
  FastOctTree tree(vg);
  std::mt19937 rng(5);
  for (int i = 0; i < 400000; ++i) {
    const Key k{std::int32_t(rng() % 64) - 20, std::int32_t(rng() % 64) - 30, std::int32_t(rng() % 64) - 40};
    const CellState s = CellState(rng() % 3);
    grid.setCell(k, s);
    tree.setCell(k, s);
    if (i % 7 == 0) {
      ASSERT_EQ(grid.getCell(k), tree.getCell(k));
    }
  }
  EXPECT_EQ(grid.getOccupiedCount(), tree.getOccupiedCount());
  EXPECT_EQ(grid.getFreeCount(), tree.getFreeCount());
  for (CellState s : {CellState::Occupied, CellState::Free}) {
    std::size_t n = 0;
    grid.forEachCell(s, [&](const Key& k) {
      ASSERT_EQ(tree.getCell(k), s);
      ++n;
    });
    EXPECT_EQ(n, s == CellState::Occupied ? tree.getOccupiedCount() : tree.getFreeCount());
  }
  grid.clear();
  EXPECT_EQ(grid.getOccupiedCount(), 0u);
  EXPECT_EQ(grid.getFreeCount(), 0u);
  for (CellState st : {CellState::Occupied, CellState::Free})
    grid.forEachCell(st, [](const Key& k) { ADD_FAILURE() << "cleared grid still holds " << toString(k); });
}

TEST(FastOccMesh, PointsUseTheSameGridAsTheTree) {
  const CellGrid vg(0.1, 0.5, 0.5, 0.5);
  FastOccMesh grid(vg, 32);
  FastOctTree tree(vg);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 2.0f);
  std::vector<float> pts;
  for (int i = 0; i < 3000; ++i) pts.insert(pts.end(), {u(rng), u(rng), u(rng)});
  grid.insertPoints(pts.data(), 3000, 3 * sizeof(float));
  tree.insertPoints(pts.data(), 3000, 3 * sizeof(float));
  EXPECT_EQ(grid.getOccupiedCount(), tree.getOccupiedCount());
  tree.forEachCell(CellState::Occupied,
                   [&](const Key& k) { EXPECT_EQ(grid.getCell(k), CellState::Occupied); });
  EXPECT_THROW(grid.setCellAtPoint(100, 0, 0, CellState::Occupied), std::out_of_range);
  EXPECT_THROW(grid.setCellAtPoint(0, std::nan(""), 0, CellState::Occupied), std::invalid_argument);
}
