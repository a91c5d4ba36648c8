// The nearest-tree-neighbour search against brute force, cell for cell and tie for tie.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <tuple>
#include <vector>

#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/search/nearest_cell_search.h>

#include "scan_data.h"

using namespace pcl::fot;

namespace {

std::int64_t distance(Metric m, const Key& a, const Key& b) {
  const std::int64_t d[3] = {std::abs(std::int64_t(a.x) - b.x), std::abs(std::int64_t(a.y) - b.y),
                             std::abs(std::int64_t(a.z) - b.z)};
  return m == Metric::Manhattan ? d[0] + d[1] + d[2] : d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

/**
 * The cells of a state nearest to q, with their distances, in the search's order (distance, then x, y, z):
 * the `count` nearest and every other cell as near as the last of them. Selecting before sorting keeps the
 * check linear in the cells, for every query of a scan.
 */
std::vector<CellMatch> bruteForce(const std::vector<Key>& cells, Metric m, const Key& q, std::size_t count) {
  std::vector<std::int64_t> d;
  d.reserve(cells.size());
  for (const Key& c : cells) d.push_back(distance(m, c, q));
  std::vector<std::int64_t> order = d;
  const std::size_t last = std::min(count, d.size()) - 1;
  std::nth_element(order.begin(), order.begin() + std::ptrdiff_t(last), order.end());
  std::vector<CellMatch> near;
  for (std::size_t i = 0; i < cells.size(); ++i)
    if (d[i] <= order[last]) near.push_back({cells[i], d[i]});
  std::sort(near.begin(), near.end(), [](const CellMatch& a, const CellMatch& b) {
    return std::tie(a.distance, a.key.x, a.key.y, a.key.z) < std::tie(b.distance, b.key.x, b.key.y, b.key.z);
  });
  return near;
}

void expectSame(const std::vector<CellMatch>& expected, const std::vector<CellMatch>& got, const char* what) {
  ASSERT_EQ(expected.size(), got.size()) << what;
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(expected[i].key, got[i].key) << what << " #" << i;
    ASSERT_EQ(expected[i].distance, got[i].distance) << what << " #" << i;
  }
}

/** Checks 1-NN, k-NN, bounded and radius queries against brute force for every query. */
void checkQueries(const FastOctTree& tree, CellState target, const std::vector<Key>& queries) {
  std::vector<Key> cells;
  tree.forEachCell(target, [&](const Key& k) { cells.push_back(k); });
  ASSERT_FALSE(cells.empty());
  for (Metric m : {Metric::Manhattan, Metric::Euclidean}) {
    NearestCellSearch search(tree, m, target);
    std::vector<CellMatch> got;
    for (const Key& q : queries) {
      const std::vector<CellMatch> all = bruteForce(cells, m, q, 13);  // k-NN takes 7, the radius the 13th
      CellMatch one;
      ASSERT_TRUE(search.nearest(q, one));
      ASSERT_EQ(one.key, all[0].key) << "1-NN of " << toString(q);
      ASSERT_EQ(one.distance, all[0].distance);
      // Without the tie rule: some target cell at the same distance.
      ASSERT_TRUE(search.anyNearest(q, one));
      ASSERT_EQ(one.distance, all[0].distance) << "any nearest of " << toString(q);
      ASSERT_EQ(distance(m, one.key, q), one.distance);
      ASSERT_EQ(tree.getCell(one.key), target);
      EXPECT_FALSE(search.anyNearest(q, one, all[0].distance - 1));
      EXPECT_TRUE(search.anyNearest(q, one, all[0].distance));
      // A true lower bound lets the walk stop early, at the right distance.
      for (std::int64_t floor : {all[0].distance - 1, all[0].distance}) {
        ASSERT_TRUE(search.anyNearest(q, one, NearestCellSearch::kUnbounded, floor));
        ASSERT_EQ(one.distance, all[0].distance) << "any nearest of " << toString(q) << " above " << floor;
      }
      search.nearestK(q, 7, got);
      expectSame(std::vector<CellMatch>(all.begin(), all.begin() + std::min<std::size_t>(7, all.size())), got,
                 "k-NN");
      const std::int64_t r = all[std::min<std::size_t>(12, all.size() - 1)].distance;
      search.radius(q, r, got);
      std::vector<CellMatch> within;
      for (const CellMatch& c : all)
        if (c.distance <= r) within.push_back(c);
      expectSame(within, got, "radius");
      // Bounded: nothing nearer than the bound means no answer.
      EXPECT_FALSE(search.nearest(q, one, all[0].distance - 1));
      EXPECT_TRUE(search.nearest(q, one, all[0].distance));
    }
  }
}

}  // namespace

TEST(NearestCellSearch, RandomClustersWithCollapsedCubes) {
  FastOctTree tree(0.1);
  std::mt19937 rng(41);
  // Scattered cells, plus full cubes that collapse into single words.
  for (int i = 0; i < 3000; ++i)
    tree.setCell(
        {std::int32_t(rng() % 400) - 200, std::int32_t(rng() % 400) - 200, std::int32_t(rng() % 100) - 50},
        (rng() % 4) ? CellState::Occupied : CellState::Free);
  for (int c = 0; c < 20; ++c) {
    const Key base{std::int32_t(rng() % 300) - 150, std::int32_t(rng() % 300) - 150,
                   std::int32_t(rng() % 60) - 30};
    const int side = 2 << (rng() % 3);
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x)
          tree.setCell({base.x + x, base.y + y, base.z + z}, CellState::Occupied);
  }
  std::vector<Key> queries;
  for (int i = 0; i < 300; ++i)
    queries.push_back(
        {std::int32_t(rng() % 600) - 300, std::int32_t(rng() % 600) - 300, std::int32_t(rng() % 200) - 100});
  queries.push_back({kMaxKey, kMinKey, 0});  // far outside the map
  checkQueries(tree, CellState::Occupied, queries);
  checkQueries(tree, CellState::Free, queries);
}

PCL_FOT_SCAN_TESTS(NearestCellSearchOnScans);

TEST_P(NearestCellSearchOnScans, ScansInSpatialOrder) {
  const CellGrid grid(0.05);
  FastOctTree target(grid), query_map(grid);
  insertPointCloud(target, *pcl_fot_test::loadScan("room_scan1.pcd"));
  insertPointCloud(query_map, *pcl_fot_test::loadScan("room_scan2.pcd"));
  std::vector<Key> queries;
  std::size_t i = 0;
  query_map.forEachCell(CellState::Occupied, [&](const Key& k) {
    if (i++ % 23 == 0) queries.push_back(k);  // Morton order: the path is reused from query to query
  });
  checkQueries(target, CellState::Occupied, queries);
}

/** The batch query against one query at a time, for every bound that changes which window answers. */
void checkBatch(const FastOctTree& tree, CellState target, const std::vector<Key>& queries) {
  for (Metric m : {Metric::Manhattan, Metric::Euclidean})
    for (std::int64_t bound :
         {NearestCellSearch::kUnbounded, std::int64_t(0), std::int64_t(5), std::int64_t(8), std::int64_t(9),
          std::int64_t(13), std::int64_t(16), std::int64_t(17), std::int64_t(40), std::int64_t(-1)}) {
      NearestCellSearch single(tree, m, target), batch(tree, m, target), threaded(tree, m, target);
      threaded.setNumberOfThreads(3);
      std::vector<CellMatch> got, got_threaded;
      std::size_t expected_found = 0;
      const std::size_t found = batch.nearest(queries, got, bound);
      ASSERT_EQ(got.size(), queries.size());
      EXPECT_EQ(threaded.nearest(queries, got_threaded, bound), found);
      for (std::size_t i = 0; i < queries.size(); ++i) {
        ASSERT_EQ(got_threaded[i].key, got[i].key) << "threads give the serial answers";
        ASSERT_EQ(got_threaded[i].distance, got[i].distance) << "threads give the serial answers";
      }
      for (std::size_t i = 0; i < queries.size(); ++i) {
        CellMatch one;
        if (single.nearest(queries[i], one, bound)) {
          ++expected_found;
          ASSERT_EQ(got[i].key, one.key) << toString(queries[i]) << " within " << bound;
          ASSERT_EQ(got[i].distance, one.distance) << toString(queries[i]) << " within " << bound;
        } else {
          ASSERT_EQ(got[i].distance, -1) << toString(queries[i]) << " within " << bound;
        }
      }
      EXPECT_EQ(found, expected_found);
    }
}

/** Every cell of the 16³ bricks around `centre`, so that bricks are dense enough for both windows. */
void addBricks(std::vector<Key>& queries, const Key& centre, int bricks) {
  for (int z = -8 * bricks; z < 8 * bricks; ++z)
    for (int y = -8 * bricks; y < 8 * bricks; ++y)
      for (int x = -8 * bricks; x < 8 * bricks; ++x)
        queries.push_back({centre.x + x, centre.y + y, centre.z + z});
}

TEST(NearestCellSearch, BatchAnswersAsSingleQueries) {
  FastOctTree tree(0.1);
  std::mt19937 rng(7);
  // Sparse surfaces with gaps wider than both windows, plus collapsed cubes.
  for (int i = 0; i < 400; ++i)
    tree.setCell(
        {std::int32_t(rng() % 120) - 60, std::int32_t(rng() % 120) - 60, 3 * std::int32_t(rng() % 3)},
        (rng() % 5) ? CellState::Occupied : CellState::Free);
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) tree.setCell({40 + x, -40 + y, 30 + z}, CellState::Occupied);
  std::vector<Key> queries;
  addBricks(queries, {0, 0, 8}, 1);      // near the surfaces
  addBricks(queries, {-16, 16, 32}, 1);  // 9 to 40 cells away: the far window and the walk
  addBricks(queries, {48, -32, 16}, 1);
  for (int i = 0; i < 500; ++i)  // scattered, a few per brick: searched one by one
    queries.push_back(
        {std::int32_t(rng() % 300) - 150, std::int32_t(rng() % 300) - 150, std::int32_t(rng() % 100) - 50});
  queries.push_back(queries[5]);  // a repeated query
  queries.push_back({kMaxKey, kMinKey, 0});
  std::shuffle(queries.begin(), queries.end(), rng);  // any order, not only the tree's
  checkBatch(tree, CellState::Occupied, queries);
  checkBatch(tree, CellState::Free, queries);

  NearestCellSearch search(tree);
  std::vector<CellMatch> got{CellMatch{{1, 2, 3}, 4}};
  EXPECT_EQ(search.nearest(std::vector<Key>{}, got), 0u);
  EXPECT_TRUE(got.empty());
  got = {CellMatch{{1, 2, 3}, 4}};
  EXPECT_THROW(search.nearest(std::vector<Key>{{0, 0, 0}, {kMaxKey + 1, 0, 0}}, got), std::out_of_range);
  ASSERT_EQ(got.size(), 1u) << "a refused batch leaves the answers alone";
  EXPECT_EQ(got[0].distance, 4);
  FastOctTree empty(0.1);
  NearestCellSearch none(empty);
  EXPECT_EQ(none.nearest(queries, got), 0u) << "an empty map answers no query";
}

TEST_P(NearestCellSearchOnScans, BatchOnScans) {
  const CellGrid grid(0.05);
  FastOctTree target(grid), query_map(grid);
  insertPointCloud(target, *pcl_fot_test::loadScan("room_scan1.pcd"));
  insertPointCloud(query_map, *pcl_fot_test::loadScan("room_scan2.pcd"));
  std::vector<Key> queries, cells;
  query_map.forEachCell(CellState::Occupied, [&](const Key& k) { queries.push_back(k); });
  target.forEachCell(CellState::Occupied, [&](const Key& k) { cells.push_back(k); });
  NearestCellSearch search(target);
  std::vector<CellMatch> got;
  ASSERT_EQ(search.nearest(queries, got), queries.size());
  for (std::size_t i = 0; i < queries.size(); i += 97) {  // brute force on a sample
    const CellMatch best = bruteForce(cells, Metric::Manhattan, queries[i], 1)[0];
    ASSERT_EQ(got[i].key, best.key) << toString(queries[i]);
    ASSERT_EQ(got[i].distance, best.distance);
  }
  checkBatch(target, CellState::Occupied, std::vector<Key>(queries.begin(), queries.begin() + 6000));
}

TEST(NearestCellSearch, EdgeCases) {
  FastOctTree empty(0.1);
  NearestCellSearch search(empty);
  CellMatch m;
  EXPECT_FALSE(search.nearest({0, 0, 0}, m)) << "an empty map has no neighbour";
  std::vector<CellMatch> got;
  EXPECT_EQ(search.nearestK({1, 2, 3}, 5, got), 0u);
  EXPECT_THROW(search.nearest({kMaxKey + 1, 0, 0}, m), std::out_of_range);
  EXPECT_THROW(NearestCellSearch(empty, Metric::Manhattan, CellState::Unknown), std::invalid_argument);

  FastOctTree one(0.1);
  one.setCell({kMaxKey, kMaxKey, kMaxKey}, CellState::Occupied);
  NearestCellSearch far(one);
  ASSERT_TRUE(far.nearest({kMinKey, kMinKey, kMinKey}, m));
  EXPECT_EQ(m.distance, 3 * (std::int64_t(kMaxKey) - kMinKey))
      << "distances across the whole key range are exact";
  NearestCellSearch far_l2(one, Metric::Euclidean);
  ASSERT_TRUE(far_l2.nearest({kMinKey, kMinKey, kMinKey}, m));
  EXPECT_EQ(m.distance, 3 * (std::int64_t(kMaxKey) - kMinKey) * (std::int64_t(kMaxKey) - kMinKey));
}
