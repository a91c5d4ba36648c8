// ψ on trees equals ψ by distance maps and by brute force, to the cell.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include <pcl/common/transforms.h>

#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/psi/distance_map.h>
#include <pcl_fot/psi/psi.h>

#include "scan_data.h"

using namespace pcl::fot;

namespace {

/** Eq. 1–2 by brute force over every pair of cells, for each cap in `caps`. */
std::vector<PsiResult> bruteForcePsi(const FastOctTree& a, const FastOctTree& b, bool include_free,
                                     const std::vector<std::int64_t>& caps) {
  std::vector<PsiResult> results(caps.size());
  for (auto& r : results) r.resolution = a.getResolution();
  for (CellState v : {CellState::Occupied, CellState::Free}) {
    if (v == CellState::Free && !include_free) continue;
    std::vector<Key> ca, cb;
    a.forEachCell(v, [&](const Key& k) { ca.push_back(k); });
    b.forEachCell(v, [&](const Key& k) { cb.push_back(k); });
    std::vector<std::int64_t> nearest;  // every cell's distance to the other map, both directions
    auto directed = [&](const std::vector<Key>& from, const std::vector<Key>& to) {
      for (const Key& p : from) {
        std::int64_t best = std::numeric_limits<std::int64_t>::max();
        for (const Key& q : to)
          best = std::min<std::int64_t>(best, std::abs(std::int64_t(p.x) - q.x) +
                                                  std::abs(std::int64_t(p.y) - q.y) +
                                                  std::abs(std::int64_t(p.z) - q.z));
        nearest.push_back(best);
      }
    };
    directed(ca, cb);
    directed(cb, ca);
    for (std::size_t i = 0; i < caps.size(); ++i) {
      PsiResult& r = results[i];
      r.cells += ca.size() + cb.size();
      const bool capped = caps[i] != std::numeric_limits<std::int64_t>::max();
      if ((ca.empty() != cb.empty()) && !capped) r.defined = false;
      for (std::int64_t d : nearest)
        if (d != std::numeric_limits<std::int64_t>::max() || capped)
          r.sum += std::uint64_t(std::min(d, caps[i]));
    }
  }
  return results;
}

void expectSame(const PsiResult& a, const PsiResult& b, const char* what) {
  EXPECT_EQ(a.sum, b.sum) << what;
  EXPECT_EQ(a.cells, b.cells) << what;
  EXPECT_EQ(a.defined, b.defined) << what;
}

/** The same cells in a tree and in a grid of the given side centred on key 0. */
struct TwinMaps {
  TwinMaps(double res, std::uint32_t side) : tree(res), grid(CellGrid(res), side) {}
  void set(const Key& k, CellState s) {
    tree.setCell(k, s);
    grid.setCell(k, s);
  }
  FastOctTree tree;
  FastOccMesh grid;
};

}  // namespace

TEST(Psi, TreesDistanceMapsAndBruteForceAgreeOnRandomMaps) {
  std::mt19937 rng(61);
  DistanceMap workspace;  // reused across trials: the distances of earlier maps must not leak into later ones
  for (int trial = 0; trial < 8; ++trial) {
    SCOPED_TRACE(trial);
    // Tiny maps (a root below a brick), dense clusters (cells within the bit-dilation reach) and sparse
    // ones (most cells further than 8, left to the tree search).
    const int n = trial < 2 ? 1 + 2 * trial : 150 + 250 * trial;
    const int spread = trial % 2 ? 100 : 40;
    TwinMaps a(0.1, 128), b(0.1, 128);
    auto cell = [&](int shift_x, int shift_y) {
      return Key{std::int32_t(rng() % spread) - spread / 2 + shift_x,
                 std::int32_t(rng() % spread) - spread / 2 + shift_y,
                 std::int32_t(rng() % spread) - spread / 2};
    };
    for (int i = 0; i < n; ++i) {
      a.set(cell(0, 0), (rng() % 3) ? CellState::Occupied : CellState::Free);
      b.set(cell(2, -2), (rng() % 3) ? CellState::Occupied : CellState::Free);
    }
    if (trial >= 2) {
      // Whole cubes, so that regions collapse: a 4³ one in both, a 16³ one (a level-4 node: key 6 is
      // aligned in tree coordinates) free in both, and another occupied in a alone.
      auto fill = [](TwinMaps& m, int x0, int y0, int z0, int side, CellState s) {
        for (int z = 0; z < side; ++z)
          for (int y = 0; y < side; ++y)
            for (int x = 0; x < side; ++x) m.set({x0 + x, y0 + y, z0 + z}, s);
      };
      fill(a, 4, -8, 0, 4, CellState::Free);
      fill(b, 4, -8, 0, 4, CellState::Free);
      fill(a, -26, -26, -26, 16, CellState::Free);
      fill(b, -26, -26, -26, 16, CellState::Free);
      fill(a, 6, 6, 6 + 16 * (trial % 3), 16, CellState::Occupied);
    }
    const std::vector<std::int64_t> caps = {std::numeric_limits<std::int64_t>::max(), 0, 3, 8, 9, 20};
    for (bool include_free : {false, true}) {
      const std::vector<PsiResult> brute = bruteForcePsi(a.tree, b.tree, include_free, caps);
      for (std::size_t i = 0; i < caps.size(); ++i) {
        SCOPED_TRACE(caps[i]);
        PsiOptions o;
        o.include_free = include_free;
        o.cap = caps[i];
        expectSame(psi(a.tree, b.tree, o), brute[i], "tree");
        if (i % 2 == 0)
          expectSame(psiByDistanceMaps(a.grid, b.grid, o), brute[i], "distance maps");
        else
          expectSame(psiByDistanceMaps(a.grid, b.grid, workspace, o), brute[i], "distance maps, reused");
        o.threads = 4;
        expectSame(psi(a.tree, b.tree, o), brute[i], "tree, four threads");
      }
    }
  }
}

TEST(Psi, CellsFarFromTheOtherMapAgreeWithBruteForce) {
  // Dense blocks and surfaces of a, with b's cells 17 to 90 cells away in every direction: beyond the
  // bit dilation's reach, where one walk settles the cells between its query and the answer.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 6; ++trial) {
    SCOPED_TRACE(trial);
    FastOctTree a(0.1), b(0.1);
    std::uniform_int_distribution<int> in_block(0, 23), far(-90, 90), coin(0, 1);
    for (int i = 0; i < 3000; ++i) {
      const int x = in_block(rng), y = in_block(rng);
      a.setCell(Key{x, y, trial % 2 ? in_block(rng) : (x + 2 * y) / 3}, CellState::Occupied);
    }
    for (int i = 0; i < 6 + 4 * trial; ++i) {
      Key k{far(rng), far(rng), far(rng)};
      if (k.x > -20 && k.x < 44 && k.y > -20 && k.y < 44 && k.z > -20 && k.z < 44)
        (coin(rng) ? k.x : k.z) += k.x < 12 ? -40 : 40;
      b.setCell(k, CellState::Occupied);
    }
    const std::vector<std::int64_t> caps = {std::numeric_limits<std::int64_t>::max(), 30, 55};
    const std::vector<PsiResult> brute = bruteForcePsi(a, b, false, caps);
    for (std::size_t i = 0; i < caps.size(); ++i) {
      SCOPED_TRACE(caps[i]);
      PsiOptions o;
      o.cap = caps[i];
      expectSame(psi(a, b, o), brute[i], "tree");
    }
  }
}

PCL_FOT_SCAN_TESTS(PsiOnScans);

TEST_P(PsiOnScans, TreesAndDistanceMapsAgreeOnScans) {
  struct Case {
    const char* a;
    const char* b;
    double res;
  };
  DistanceMap workspace;  // reused by the second case, whose cube has another size
  for (const Case& c : {Case{"kinect_capture0001.pcd", "kinect_capture0002.pcd", 0.02},
                        Case{"room_scan1.pcd", "room_scan2.pcd", 0.1}}) {
    SCOPED_TRACE(c.a);
    const CellGrid grid(c.res);
    FastOctTree ta(grid), tb(grid);
    const auto ca = pcl_fot_test::loadScan(c.a), cb = pcl_fot_test::loadScan(c.b);
    insertPointCloud(ta, *ca);
    insertPointCloud(tb, *cb);
    // The grids' cubes start at the scans' lowest cell and are just large enough to hold both.
    Key lo{kMaxKey, kMaxKey, kMaxKey}, hi{kMinKey, kMinKey, kMinKey};
    for (const FastOctTree* t : {&ta, &tb})
      t->forEachCell(CellState::Occupied, [&](const Key& k) {
        lo = Key{std::min(lo.x, k.x), std::min(lo.y, k.y), std::min(lo.z, k.z)};
        hi = Key{std::max(hi.x, k.x), std::max(hi.y, k.y), std::max(hi.z, k.z)};
      });
    const std::uint32_t side = std::uint32_t(std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z})) + 1;
    FastOccMesh ga(grid, side, lo), gb(grid, side, lo);
    ASSERT_EQ(insertPointCloud(ga, *ca).out_of_range, 0u) << "the grid must hold the whole scan";
    ASSERT_EQ(insertPointCloud(gb, *cb).out_of_range, 0u);
    const PsiResult tree = psi(ta, tb), maps = psiByDistanceMaps(ga, gb);
    expectSame(tree, maps, "occupied");
    EXPECT_GT(tree.sum, 0u);
    PsiOptions capped;
    capped.cap = 5;
    capped.threads = 0;
    expectSame(psi(ta, tb, capped), psiByDistanceMaps(ga, gb, capped), "capped, all threads");
    expectSame(tree, psiByDistanceMaps(ga, gb, workspace), "distance maps in a reused workspace");
  }
}

TEST_P(PsiOnScans, ZeroForEqualMapsAndSymmetric) {
  const CellGrid grid(0.05);
  FastOctTree a(grid), b(grid);
  insertPointCloud(a, *pcl_fot_test::loadScan("room_scan1.pcd"));
  insertPointCloud(b, *pcl_fot_test::loadScan("room_scan2.pcd"));
  EXPECT_EQ(psi(a, a).sum, 0u);
  EXPECT_EQ(psi(a, FastOctTree(a)).sum, 0u);
  const PsiResult ab = psi(a, b), ba = psi(b, a);
  EXPECT_EQ(ab.sum, ba.sum);
  EXPECT_EQ(ab.cells, ba.cells);
  EXPECT_DOUBLE_EQ(ab.metres(), double(ab.sum) * 0.05);
  EXPECT_DOUBLE_EQ(ab.mean(), double(ab.sum) / double(ab.cells));
}

TEST_P(PsiOnScans, GrowsAsAScanIsShiftedFromItself) {
  const auto cloud = pcl_fot_test::loadScan("kinect_capture0001.pcd");
  const double res = 0.02;
  FastOctTree base(res);
  insertPointCloud(base, *cloud);
  std::uint64_t last = 0;
  for (int step = 1; step <= 10; ++step) {
    pcl::PointCloud<pcl::PointXYZ> shifted;
    pcl::transformPointCloud(*cloud, shifted,
                             Eigen::Affine3f(Eigen::Translation3f(float(step * res), 0.0f, 0.0f)));
    FastOctTree moved(res);
    insertPointCloud(moved, shifted);
    const std::uint64_t s = psi(base, moved).sum;
    EXPECT_GT(s, last) << "shift of " << step << " cells";
    last = s;
  }
}

TEST(Psi, ErrorsAndEmptySides) {
  FastOctTree a(0.1), b(0.2), c(0.1, 0.05), empty(0.1);
  a.setCell({1, 2, 3}, CellState::Occupied);
  EXPECT_THROW(psi(a, b), std::invalid_argument) << "different resolutions";
  EXPECT_THROW(psi(a, c), std::invalid_argument) << "different origins";
  PsiOptions negative;
  negative.cap = -1;
  EXPECT_THROW(psi(a, a, negative), std::invalid_argument);
  EXPECT_FALSE(psi(a, empty).defined) << "no occupied cell to measure to";
  EXPECT_TRUE(psi(empty, empty).defined);
  EXPECT_EQ(psi(empty, empty).sum, 0u);
  PsiOptions capped;
  capped.cap = 7;
  const PsiResult r = psi(a, empty, capped);
  EXPECT_TRUE(r.defined);
  EXPECT_EQ(r.sum, 7u) << "each unmatched cell counts the cap";
  FastOccMesh g1(CellGrid(0.1), 16), g2(CellGrid(0.1), 32);
  EXPECT_THROW(psiByDistanceMaps(g1, g2), std::invalid_argument);
}
