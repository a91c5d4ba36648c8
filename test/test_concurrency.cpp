// The concurrency contract: const queries from many threads at once on one map, each thread with its own
// accessor or searcher, give what the serial path gives. Built and run under ThreadSanitizer as well.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <random>
#include <stdexcept>
#include <thread>

#include <pcl/common/common.h>
#include <pcl/common/point_tests.h>

#include <pcl_fot/detail/worker_threads.h>
#include <pcl_fot/mapping/cast_ray.h>
#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_search.h>
#include <pcl_fot/pcl/search/fast_oct_tree_search.h>
#include <pcl_fot/psi/psi.h>
#include <pcl_fot/search/nearest_cell_search.h>
#include <pcl_fot/tree/accessor.h>

#include "scan_data.h"

using namespace pcl::fot;

namespace {

constexpr unsigned kThreads = 4;

const FastOctTree& roomMap() {
  return pcl_fot_test::perScanSet<FastOctTree>([] {
    FastOctTree t(0.05);
    insertScan(t, *pcl_fot_test::loadScan("room_scan1.pcd"));
    return t;
  });
}

std::vector<Key> queryKeys(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<Key> keys;
  for (std::size_t i = 0; i < n; ++i)
    keys.push_back(
        {std::int32_t(rng() % 200) - 100, std::int32_t(rng() % 200) - 100, std::int32_t(rng() % 60) - 10});
  return keys;
}

/** Runs body(thread) on kThreads threads at once, released together. */
template <typename Body>
void together(Body&& body) {
  std::atomic<unsigned> ready{0};
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      ++ready;
      while (ready < kThreads) std::this_thread::yield();
      body(t);
    });
  for (auto& th : threads) th.join();
}

}  // namespace

PCL_FOT_SCAN_TESTS(Concurrency);

TEST_P(Concurrency, CellReadsNearestCellsAndRayCasts) {
  const FastOctTree& map = roomMap();
  const std::vector<Key> keys = queryKeys(20000, 1);
  std::vector<CellState> states;
  std::vector<std::int64_t> nearest;
  std::vector<Key> hits;
  {
    ConstAccessor cells(map);
    NearestCellSearch search(map);
    for (const Key& k : keys) {
      states.push_back(cells.getCell(k));
      CellMatch m;
      nearest.push_back(search.nearest(k, m) ? m.distance : -1);
    }
    for (std::size_t i = 0; i < 2000; ++i) {
      const float origin[3] = {0, 0, 0}, dir[3] = {std::cos(0.01f * i), std::sin(0.01f * i), 0.1f};
      Key hit{};
      castRay(map, origin, dir, hit, 30.0f);
      hits.push_back(hit);
    }
  }
  together([&](unsigned t) {
    ConstAccessor cells(map);  // one accessor and one searcher per thread
    NearestCellSearch search(map);
    for (std::size_t i = t; i < keys.size(); i += kThreads) {
      ASSERT_EQ(cells.getCell(keys[i]), states[i]);
      CellMatch m;
      ASSERT_EQ(search.nearest(keys[i], m) ? m.distance : -1, nearest[i]);
    }
    for (std::size_t i = t; i < hits.size(); i += kThreads) {
      const float origin[3] = {0, 0, 0}, dir[3] = {std::cos(0.01f * i), std::sin(0.01f * i), 0.1f};
      Key hit{};
      castRay(map, origin, dir, hit, 30.0f);
      ASSERT_EQ(hit, hits[i]);
    }
    std::size_t regions = 0;
    map.forEachRegionInBox({-20, -20, 0}, {20, 20, 20}, [&](const Region&) { ++regions; });
    ASSERT_GT(regions, 0u);
  });
}

TEST_P(Concurrency, PsiAndBatchSearchesMatchTheSerialPath) {
  const FastOctTree& a = roomMap();
  FastOctTree b(0.05);
  insertScan(b, *pcl_fot_test::loadScan("room_scan2.pcd"));
  PsiOptions serial, parallel;
  parallel.threads = kThreads;
  parallel.include_free = serial.include_free = true;
  const PsiResult expected = psi(a, b, serial);
  together([&](unsigned) {  // several ψ at once, each itself threaded
    const PsiResult r = psi(a, b, parallel);
    ASSERT_EQ(r.sum, expected.sum);
    ASSERT_EQ(r.cells, expected.cells);
  });

  std::vector<Key> cells;  // the batch cell query, several at once, each itself threaded
  b.forEachCell(CellState::Occupied, [&](const Key& k) { cells.push_back(k); });
  std::vector<CellMatch> serial_cells;
  NearestCellSearch(a).nearest(cells, serial_cells);
  together([&](unsigned) {
    NearestCellSearch search(a);
    search.setNumberOfThreads(kThreads);
    std::vector<CellMatch> got;
    search.nearest(cells, got);
    for (std::size_t i = 0; i < cells.size(); ++i) {
      ASSERT_EQ(got[i].key, serial_cells[i].key);
      ASSERT_EQ(got[i].distance, serial_cells[i].distance);
    }
  });

  const auto cloud = pcl_fot_test::loadScan("kinect_capture0001.pcd");
  const auto queries = pcl_fot_test::loadScan("kinect_capture0002.pcd");
  pcl::Indices finite;
  for (std::size_t i = 0; i < queries->size(); i += 7)
    if (pcl::isFinite((*queries)[i])) finite.push_back(pcl::index_t(i));
  search::FastOctTreeSearch<pcl::PointXYZ> index(0.03);
  index.setInputCloud(cloud);
  std::vector<pcl::Indices> serial_k, threaded_k, serial_r, threaded_r;
  std::vector<std::vector<float>> serial_kd, threaded_kd, serial_rd, threaded_rd;
  index.nearestKSearch(*queries, finite, 5, serial_k, serial_kd);
  index.radiusSearch(*queries, finite, 0.02, serial_r, serial_rd, 20);
  index.setNumberOfThreads(kThreads);
  index.nearestKSearch(*queries, finite, 5, threaded_k, threaded_kd);
  index.radiusSearch(*queries, finite, 0.02, threaded_r, threaded_rd, 20);
  EXPECT_EQ(threaded_k, serial_k);
  EXPECT_EQ(threaded_kd, serial_kd);
  EXPECT_EQ(threaded_r, serial_r);
  EXPECT_EQ(threaded_rd, serial_rd);
  // And single queries from many threads at once on the shared index.
  together([&](unsigned t) {
    pcl::Indices idx;
    std::vector<float> d;
    for (std::size_t i = t; i < finite.size(); i += kThreads) {
      index.nearestKSearch((*queries)[std::size_t(finite[i])], 5, idx, d);
      ASSERT_EQ(idx, serial_k[i]);
    }
  });
}

TEST_P(Concurrency, SearchQueriesBetweenUpdates) {
  // Queries from many threads at once, then an update alone, in turn: a sliding window of a room scan.
  const auto cloud = pcl_fot_test::loadScan("room_scan1.pcd");
  pcl::PointCloud<pcl::PointXYZ> frames[4];
  for (std::size_t i = 0; i < cloud->size(); ++i) frames[i % 4].push_back((*cloud)[i]);
  search::FastOctTreeSearch<pcl::PointXYZ> window;
  pcl::Indices added[4];  // each frame's indices, as addPoints gave them
  window.addPoints(frames[0], added[0]);
  for (int f = 1; f < 4; ++f) {
    window.addPoints(frames[f], added[f]);
    pcl::Indices oldest;
    for (std::size_t i = 0; i < added[f - 1].size(); i += 2) oldest.push_back(added[f - 1][i]);
    window.removePoints(oldest);
    std::vector<pcl::Indices> serial(frames[f].size() / 17 + 1);
    std::vector<float> d;
    for (std::size_t i = 0; i < frames[f].size(); i += 17)
      window.nearestKSearch(frames[f][i], 3, serial[i / 17], d);
    together([&](unsigned t) {
      pcl::Indices idx;
      std::vector<float> dist;
      for (std::size_t i = 17 * t; i < frames[f].size(); i += 17 * kThreads) {
        window.nearestKSearch(frames[f][i], 3, idx, dist);
        ASSERT_EQ(idx, serial[i / 17]);
      }
    });
  }
}

TEST_P(Concurrency, SnapshotsAreReadWhileTheSearchUpdates) {
  // getInputCloud() is a snapshot: threads read it, and search it with a search of their own, while one
  // thread slides the window it came from. The window writes to a copy of its own (issue 47: it wrote to
  // the snapshot in place, reallocating it under the readers). Only the API that predates the fix is used.
  const auto cloud = pcl_fot_test::loadScan("room_scan1.pcd");
  pcl::PointCloud<pcl::PointXYZ> frames[6];
  for (std::size_t i = 0; i < cloud->size(); ++i) frames[i % 6].push_back((*cloud)[i]);
  Eigen::Vector4f lo, hi;
  pcl::getMinMax3D(*cloud, lo, hi);
  search::FastOctTreeSearch<pcl::PointXYZ> window;
  window.addPoints(frames[0]);
  window.addPoints(frames[1]);
  const pcl::PointCloud<pcl::PointXYZ>::ConstPtr snapshot = window.getInputCloud();
  const pcl::PointCloud<pcl::PointXYZ> before = *snapshot;
  search::FastOctTreeSearch<pcl::PointXYZ> reader;
  reader.setInputCloud(snapshot);
  std::vector<pcl::Indices> serial(snapshot->size() / 17 + 1);
  std::vector<float> d;
  for (std::size_t i = 0; i < snapshot->size(); i += 17)
    reader.nearestKSearch((*snapshot)[i], 3, serial[i / 17], d);
  together([&](unsigned t) {
    if (t == 0) {  // the window changes: a frame in, a slab of the room out, its indices free for the next
      const float step = 0.25f * (hi.x() - lo.x());
      for (int f = 2; f < 6; ++f) {
        window.addPoints(frames[f]);
        const float x = lo.x() + float(f - 2) * step;
        window.removePoints(Eigen::Vector3f(x, lo.y(), lo.z()), Eigen::Vector3f(x + step, hi.y(), hi.z()));
      }
      return;
    }
    pcl::Indices idx;
    std::vector<float> dist;
    for (int round = 0; round < 3; ++round)
      for (std::size_t i = 17 * t; i < snapshot->size(); i += 17 * kThreads) {
        reader.nearestKSearch((*snapshot)[i], 3, idx, dist);
        ASSERT_EQ(idx, serial[i / 17]);
      }
  });
  ASSERT_EQ(snapshot->size(), before.size());
  for (std::size_t i = 0; i < before.size(); ++i)
    ASSERT_EQ(std::memcmp(&(*snapshot)[i].x, &before[i].x, 3 * sizeof(float)), 0) << "point " << i;
  EXPECT_NE(window.getInputCloud(), snapshot);
}

TEST_P(Concurrency, OctreeLookAlikeSearchesFromManyThreads) {
  // The first queries build the octree's point and branch indices: threads race to them.
  const auto scan = pcl_fot_test::loadScan("room_scan2.pcd");
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (std::size_t i = 0; i < scan->size(); i += 4) cloud->push_back((*scan)[i]);
  struct Answer {
    pcl::Indices knn, radius;
    pcl::index_t approx;
    bool operator==(const Answer& o) const {
      return knn == o.knn && radius == o.radius && approx == o.approx;
    }
  };
  const auto ask = [](const OctreePointCloudSearch<pcl::PointXYZ>& octree, const pcl::PointXYZ& q) {
    Answer a;
    std::vector<float> d;
    float approx_distance;
    octree.nearestKSearch(q, 5, a.knn, d);
    octree.radiusSearch(q, 0.2, a.radius, d);
    octree.approxNearestSearch(q, a.approx, approx_distance);
    return a;
  };
  const auto fill = [&](OctreePointCloudSearch<pcl::PointXYZ>& octree) {
    octree.setInputCloud(cloud);
    octree.addPointsFromInputCloud();
  };
  OctreePointCloudSearch<pcl::PointXYZ> serial_octree(0.1), shared(0.1);
  fill(serial_octree);
  fill(shared);
  std::vector<Answer> serial;
  for (std::size_t i = 0; i < cloud->size(); i += 13) serial.push_back(ask(serial_octree, (*cloud)[i]));
  together([&](unsigned t) {
    for (std::size_t i = 13 * t; i < cloud->size(); i += 13 * kThreads)
      ASSERT_TRUE(ask(shared, (*cloud)[i]) == serial[i / 13]) << "query " << i;
  });
  // Leaf walks from many threads share the branch index. Each takes every leaf's container, which gets its
  // points from the build's runs as the threads race to it, while voxel searches read the same leaves.
  std::size_t leaves = 0, points = 0;
  for (auto it = serial_octree.leaf_depth_begin(); it != serial_octree.leaf_depth_end(); ++it)
    ++leaves, points += it.getLeafContainer().getSize();
  OctreePointCloudSearch<pcl::PointXYZ> walked(0.1);
  fill(walked);
  together([&](unsigned t) {
    std::size_t n = 0, held = 0;
    for (auto it = walked.leaf_depth_begin(); it != walked.leaf_depth_end(); ++it) {
      ++n, held += it.getLeafContainer().getSize();
      pcl::Indices voxel, serial_voxel;
      const pcl::PointXYZ& q = (*cloud)[(n * kThreads + t) % cloud->size()];
      ASSERT_EQ(walked.voxelSearch(q, voxel), serial_octree.voxelSearch(q, serial_voxel));
      ASSERT_EQ(voxel, serial_voxel);
    }
    ASSERT_EQ(n, leaves);
    ASSERT_EQ(held, points);
  });
}

namespace {

/** Equal canonical pools: the same words, and the same values bit for bit (an unknown cell's is NaN). */
::testing::AssertionResult sameWords(const FastOctTree& a, const FastOctTree& b) {
  const FastOctTree::CanonicalPool pa = a.canonicalPool(), pb = b.canonicalPool();
  if (pa.words != pb.words) return ::testing::AssertionFailure() << "the pools' words differ";
  if (pa.values.size() != pb.values.size() ||
      (!pa.values.empty() &&
       std::memcmp(pa.values.data(), pb.values.data(), pa.values.size() * sizeof(float)) != 0))
    return ::testing::AssertionFailure() << "the pools' values differ";
  return ::testing::AssertionSuccess();
}

/** Inserts the scans with `threads` threads; the statistics of all scans are summed in `total`. */
FastOctTree mapOnThreads(const std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr>& scans, UpdateRule rule,
                         unsigned threads, ScanStats& total) {
  FastOctTree t(0.05);
  t.setUpdateRule(rule);
  ScanOptions options;
  options.threads = threads;
  total = ScanStats();
  for (const auto& scan : scans) {
    const ScanStats s = insertScan(t, *scan, options);
    total.ray_cells += s.ray_cells;
    total.skipped_cells += s.skipped_cells;
    total.free_cells += s.free_cells;
  }
  return t;
}

/** One, two, three and eight threads build the same map, word for word, and count the same cells. */
void expectSameMapOnAnyThreadCount(const std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr>& scans) {
  for (UpdateRule rule : {UpdateRule::LogOdds, UpdateRule::Binary}) {
    SCOPED_TRACE(rule == UpdateRule::LogOdds ? "log-odds" : "binary");
    ScanStats one_stats;
    const FastOctTree one = mapOnThreads(scans, rule, 1, one_stats);
    EXPECT_GT(one.getFreeCount(), 0u);
    for (unsigned threads : {2u, 3u, 8u}) {
      ScanStats stats;
      EXPECT_TRUE(sameWords(mapOnThreads(scans, rule, threads, stats), one)) << threads << " threads";
      EXPECT_EQ(stats.ray_cells, one_stats.ray_cells) << threads << " threads";
      if (rule == UpdateRule::LogOdds) {
        EXPECT_EQ(stats.free_cells, one_stats.free_cells) << threads << " threads";
      }
    }
  }
}

}  // namespace

TEST_P(Concurrency, ScanInsertionOnAnyThreadCountGivesTheSameMapWordForWord) {
  expectSameMapOnAnyThreadCount({pcl_fot_test::loadScan("room_scan1.pcd")});
}

TEST(ConcurrencyOnRandomScans, ScanInsertionOnAnyThreadCountGivesTheSameMapWordForWord) {
  // Points scattered around the sensor, near and far, NaNs among them: rays enough for eight threads.
  std::mt19937 rng(47);
  std::normal_distribution<float> spread(0.0f, 2.0f);
  pcl::PointCloud<pcl::PointXYZ>::Ptr scan(new pcl::PointCloud<pcl::PointXYZ>);
  for (int i = 0; i < 36000; ++i)
    scan->push_back(i % 997 == 0 ? pcl::PointXYZ(NAN, 0.0f, 0.0f)
                                 : pcl::PointXYZ(spread(rng), spread(rng), 0.5f * spread(rng)));
  scan->sensor_origin_ = Eigen::Vector4f(0.3f, -0.2f, 0.1f, 1.0f);
  expectSameMapOnAnyThreadCount({scan});

  // One scan into an empty log-odds map: each cell it marks free holds one miss, so the free cells counted
  // while inserting are the map's free cells.
  ScanStats stats;
  const FastOctTree one = mapOnThreads({scan}, UpdateRule::LogOdds, 2, stats);
  EXPECT_EQ(stats.free_cells, one.getFreeCount());
  EXPECT_LT(stats.free_cells, stats.ray_cells) << "rays cross cells near the sensor again and again";
}

TEST(ConcurrencyOnRandomScans, ADenseFrameInBundlesOnAnyThreadCountGivesTheSameMapWordForWord) {
  // A depth camera's frame, dense enough that its rays are bundled: the threads split the bundles' setup,
  // binning and sweep as well as the walks, unevenly at three.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> bump(0.0f, 0.4f);
  pcl::PointCloud<pcl::PointXYZ>::Ptr frame(new pcl::PointCloud<pcl::PointXYZ>);
  for (int y = 0; y < 180; ++y)
    for (int x = 0; x < 240; ++x) {
      const float dx = 1.1f * (float(x) / 239.0f - 0.5f), dy = 0.8f * (float(y) / 179.0f - 0.5f);
      const float t = (x / 40 + y / 30) % 3 == 0 ? 2.0f - bump(rng) : 3.0f;
      frame->push_back(pcl::PointXYZ(t * dx, t * dy, t));
    }
  ScanStats stats;
  mapOnThreads({frame}, UpdateRule::LogOdds, 1, stats);
  ASSERT_GT(stats.skipped_cells, stats.ray_cells / 2) << "the frame's rays are bundled";
  expectSameMapOnAnyThreadCount({frame});
}

TEST_P(Concurrency, WorkerThreadsAreBoundedAndErrorsReachTheCaller) {
  const std::size_t hardware = std::max(1u, std::thread::hardware_concurrency());
  EXPECT_EQ(detail::workerCount(0, 1000), std::min<std::size_t>(hardware, 1000));
  EXPECT_EQ(detail::workerCount(4'000'000'000u, 1'000'000'000), 4 * hardware);
  EXPECT_EQ(detail::workerCount(3, 2), 2u);
  EXPECT_EQ(detail::workerCount(3, 0), 1u);

  std::atomic<unsigned> ran{0};
  EXPECT_THROW(detail::runWorkers(3,
                                  [&](std::size_t w) {
                                    ++ran;
                                    if (w == 1) throw std::runtime_error("share 1");
                                  }),
               std::runtime_error);
  EXPECT_EQ(ran.load(), 3u) << "every share ran before the error was passed on";

  // A request for four billion threads: the same ψ, from at most four per hardware thread.
  const FastOctTree& a = roomMap();
  FastOctTree b(0.05);
  insertScan(b, *pcl_fot_test::loadScan("room_scan2.pcd"));
  PsiOptions many;
  many.threads = 4'000'000'000u;
  EXPECT_EQ(psi(a, b, many).sum, psi(a, b).sum);
}
