// FastOctTreeSearch updated in place: after any sequence of additions and removals, its answers equal brute
// force over the points held, and a new search of them. Removed points' indices go to later points, so a
// window costs the memory of the points it holds; getInputCloud() is a snapshot no update changes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>

#include <pcl/common/common.h>
#include <pcl/common/point_tests.h>

#include <pcl_fot/pcl/search/fast_oct_tree_search.h>

#include "scan_data.h"

using pcl::PointXYZ;
using Cloud = pcl::PointCloud<PointXYZ>;
using Search = pcl::fot::search::FastOctTreeSearch<PointXYZ>;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/** Points on a coarse lattice, so that many are equally near a query, some repeated, some NaN. */
Cloud latticeBatch(std::mt19937& rng, std::size_t n) {
  Cloud c;
  std::uniform_int_distribution<int> cell(-6, 6), odd(0, 19);
  for (std::size_t i = 0; i < n; ++i) {
    if (odd(rng) == 0) {
      c.push_back(PointXYZ(kNaN, 0.0f, 0.0f));
    } else if (odd(rng) == 0 && !c.empty()) {
      c.push_back(c[rng() % c.size()]);  // a duplicate, perhaps of a NaN point
    } else {
      c.push_back(PointXYZ(0.25f * float(cell(rng)), 0.25f * float(cell(rng)), 0.25f * float(cell(rng))));
    }
  }
  return c;
}

struct Hit {
  float distance;
  int index;
  bool operator<(const Hit& o) const {
    return distance < o.distance || (distance == o.distance && index < o.index);
  }
};

/** Every held point by distance (FLANN's float sum), ties to the smaller index. */
std::vector<Hit> bruteForce(const Cloud& cloud, const std::vector<bool>& held, const PointXYZ& q) {
  std::vector<Hit> hits;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!held[i]) continue;
    const float dx = cloud[i].x - q.x, dy = cloud[i].y - q.y, dz = cloud[i].z - q.z;
    hits.push_back({dx * dx + dy * dy + dz * dz, int(i)});
  }
  std::sort(hits.begin(), hits.end());
  return hits;
}

/** k-NN and radius searches of random queries: the same indices and distances as brute force. */
void expectBruteForce(const Search& search, const std::vector<bool>& held, std::mt19937& rng) {
  const Cloud none;
  const Cloud& cloud = search.getInputCloud() ? *search.getInputCloud() : none;
  std::uniform_real_distribution<float> coord(-2.0f, 2.0f);
  pcl::Indices got;
  std::vector<float> d;
  for (int i = 0; i < 20; ++i) {
    const PointXYZ q(coord(rng), coord(rng), coord(rng));
    const std::vector<Hit> all = bruteForce(cloud, held, q);
    for (int k : {1, 7, 40}) {
      const std::size_t want = std::min<std::size_t>(std::size_t(k), all.size());
      ASSERT_EQ(search.nearestKSearch(q, k, got, d), int(want)) << "k = " << k;
      for (std::size_t j = 0; j < want; ++j) {
        ASSERT_EQ(got[j], all[j].index) << "k = " << k << ", result " << j;
        ASSERT_EQ(d[j], all[j].distance);
      }
    }
    const double radius = 0.6;
    std::size_t within = 0;
    while (within < all.size() && double(all[within].distance) <= radius * radius) ++within;
    ASSERT_EQ(search.radiusSearch(q, radius, got, d), int(within));
    for (std::size_t j = 0; j < within; ++j) ASSERT_EQ(got[j], all[j].index);
  }
}

std::size_t heldCount(const std::vector<bool>& held) {
  return std::size_t(std::count(held.begin(), held.end(), true));
}

/** The same coordinates, bit for bit (NaN included). */
bool sameXYZ(const PointXYZ& a, const PointXYZ& b) {
  return std::memcmp(&a.x, &b.x, sizeof(float)) == 0 && std::memcmp(&a.y, &b.y, sizeof(float)) == 0 &&
         std::memcmp(&a.z, &b.z, sizeof(float)) == 0;
}

bool sameClouds(const Cloud& a, const Cloud& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!sameXYZ(a[i], b[i])) return false;
  return true;
}

}  // namespace

TEST(SearchUpdates, RandomSequencesEqualBruteForce) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    std::mt19937 rng(seed);
    // Half the runs start from setInputCloud, half from nothing; half pick their cell edge, and one of those
    // has cells so large that they are crowded (split into boxes, points added and removed among them).
    Search search = seed % 2 ? Search() : Search(seed == 4 ? 2.0 : 0.3);
    std::vector<bool> held;  // by index into getInputCloud()
    std::size_t most_held = 0;
    if (seed % 3 != 0) {
      auto first = std::make_shared<Cloud>(latticeBatch(rng, 300));
      search.setInputCloud(first);
      for (const auto& p : *first) held.push_back(pcl::isFinite(p));
      most_held = first->size();  // the cloud is the input, NaN points included
    }
    // Now and then a snapshot is held across a step: the step must leave it as it was.
    Cloud::ConstPtr snapshot;
    Cloud snapshot_copy;
    for (int step = 0; step < 40; ++step) {
      const Cloud& cloud = search.getInputCloud() ? *search.getInputCloud() : Cloud();
      if (rng() % 3 == 0 && search.getInputCloud()) {
        snapshot = search.getInputCloud();
        snapshot_copy = *snapshot;
      }
      switch (rng() % 5) {
        case 0:
        case 1: {
          const Cloud batch = latticeBatch(rng, rng() % 120);
          std::size_t finite = 0;
          for (const auto& p : batch) finite += pcl::isFinite(p);
          pcl::Indices ids;
          ASSERT_EQ(search.addPoints(batch, ids), finite);
          ASSERT_EQ(ids.size(), batch.size());
          const Cloud& now = *search.getInputCloud();
          held.resize(now.size(), false);
          // Free indices first, lowest first, then the cloud's end: a batch's indices increase, and the
          // cloud grows only when none is free, so it is as large as the most points held at once.
          std::vector<bool> was_free(held.size());
          for (std::size_t i = 0; i < held.size(); ++i) was_free[i] = !held[i];
          int last = -1;
          for (std::size_t i = 0; i < batch.size(); ++i) {
            if (!pcl::isFinite(batch[i])) {
              ASSERT_EQ(ids[i], pcl::UNAVAILABLE);
              continue;
            }
            ASSERT_GT(ids[i], last);
            ASSERT_LT(std::size_t(ids[i]), now.size());
            ASSERT_FALSE(held[std::size_t(ids[i])]) << "index " << ids[i] << " is held already";
            // No free index below this one was passed over.
            for (int j = last + 1; j < ids[i]; ++j) ASSERT_FALSE(was_free[std::size_t(j)]) << j;
            ASSERT_TRUE(sameXYZ(now[std::size_t(ids[i])], batch[i]));
            held[std::size_t(ids[i])] = true;
            last = ids[i];
          }
          most_held = std::max(most_held, heldCount(held));
          ASSERT_EQ(now.size(), most_held);
          break;
        }
        case 2: {  // some held, some removed already, some twice
          pcl::Indices doomed;
          for (std::size_t i = 0; i < cloud.size(); ++i)
            if (rng() % 4 == 0) doomed.push_back(int(i));
          if (!doomed.empty()) doomed.push_back(doomed.front());
          std::size_t expected = 0;
          for (int i : doomed) expected += held[std::size_t(i)], held[std::size_t(i)] = false;
          ASSERT_EQ(search.removePoints(doomed), expected);
          break;
        }
        default: {
          const float a = 0.25f * float(int(rng() % 9) - 4), b = a + 0.25f * float(rng() % 8);
          const Eigen::Vector3f lo(a, -1.5f, a), hi(b, 1.0f, b);
          const bool inside = rng() % 2;
          std::size_t expected = 0;
          for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (!held[i]) continue;
            const Eigen::Vector3f p = cloud[i].getVector3fMap();
            const bool in = (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
            if (in == inside) ++expected, held[i] = false;
          }
          ASSERT_EQ(inside ? search.removePoints(lo, hi) : search.removeOutsideBox(lo, hi), expected);
        }
      }
      ASSERT_EQ(search.size(), heldCount(held));
      if (snapshot) {
        ASSERT_TRUE(sameClouds(*snapshot, snapshot_copy)) << "seed " << seed << ", step " << step;
        snapshot.reset();
      }
      ASSERT_NO_FATAL_FAILURE(expectBruteForce(search, held, rng)) << "seed " << seed << ", step " << step;
    }
  }
}

PCL_FOT_SCAN_TESTS(SearchUpdatesOnScans);

TEST_P(SearchUpdatesOnScans, AnUpdatedScanAnswersAsANewSearchOfItsPoints) {
  const Cloud::Ptr room = pcl_fot_test::loadScan("room_scan1.pcd");
  const Cloud::Ptr other = pcl_fot_test::loadScan("room_scan2.pcd");
  Search updated;
  updated.setInputCloud(room);
  // A sliding window in miniature: the far half of the room goes, the other scan comes, a box is cut out.
  Eigen::Vector4f lo, hi;
  pcl::getMinMax3D(*room, lo, hi);
  const Eigen::Vector3f mid = 0.5f * (lo + hi).head<3>();
  updated.removeOutsideBox(lo.head<3>(), Eigen::Vector3f(mid.x(), hi.y(), hi.z()));
  pcl::Indices added;  // the other scan's points go where the far half and the NaN points were
  updated.addPoints(*other, added);
  updated.removePoints(mid - Eigen::Vector3f::Constant(0.5f), mid + Eigen::Vector3f::Constant(0.5f));

  const Cloud& all = *updated.getInputCloud();
  EXPECT_LT(all.size(), room->size() + other->size());
  std::vector<bool> held(all.size(), false);
  for (std::size_t i = 0; i < room->size(); ++i)
    held[i] = pcl::isFinite((*room)[i]) && (*room)[i].x <= mid.x();  // the far half went
  for (const int i : added)
    if (i != pcl::UNAVAILABLE) held[std::size_t(i)] = true;
  pcl::IndicesPtr survivors(new pcl::Indices);
  pcl::Indices got, want;
  std::vector<float> dg, dw;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (!held[i]) continue;
    const Eigen::Vector3f p = all[i].getVector3fMap();
    const bool cut = (p.array() >= (mid.array() - 0.5f)).all() && (p.array() <= (mid.array() + 0.5f)).all();
    if (!cut) survivors->push_back(int(i));
  }
  ASSERT_EQ(survivors->size(), updated.size());
  Search fresh;
  fresh.setInputCloud(updated.getInputCloud(), survivors);
  for (std::size_t i = 0; i < all.size(); i += 11) {
    if (!pcl::isFinite(all[i])) continue;  // no results; the placeholder is any point held (see the class)
    for (int k : {1, 10}) {
      ASSERT_EQ(updated.nearestKSearch(all[i], k, got, dg), fresh.nearestKSearch(all[i], k, want, dw));
      ASSERT_EQ(got, want);
      ASSERT_EQ(dg, dw);
    }
    ASSERT_EQ(updated.radiusSearch(all[i], 0.01, got, dg), fresh.radiusSearch(all[i], 0.01, want, dw));
    ASSERT_EQ(got, want);
  }
  // PCL's index-based queries reach the added points.
  const auto one = std::find_if(added.begin(), added.end(), [&](int i) {
    return i != pcl::UNAVAILABLE && std::binary_search(survivors->begin(), survivors->end(), i);
  });
  ASSERT_NE(one, added.end());
  updated.nearestKSearch(*one, 1, got, dg);
  EXPECT_EQ(dg[0], 0.0f);
}

TEST(SearchUpdates, EmptiedAndRefilled) {
  Search search(0.1);
  pcl::Indices got;
  std::vector<float> d;
  Cloud batch;
  batch.push_back(PointXYZ(1, 2, 3));
  batch.push_back(PointXYZ(kNaN, 2, 3));
  batch.push_back(PointXYZ(1, 2, 3.5f));
  pcl::Indices ids;
  EXPECT_EQ(search.addPoints(batch, ids), 2u);  // no input cloud before: the additions are the cloud
  EXPECT_EQ(ids, (pcl::Indices{0, pcl::UNAVAILABLE, 1}));  // the NaN point takes no index
  EXPECT_EQ(search.getInputCloud()->size(), 2u);
  EXPECT_EQ(search.getSkippedCount(), 1u);
  EXPECT_EQ(search.nearestKSearch(PointXYZ(1, 2, 3.4f), 1, got, d), 1);
  EXPECT_EQ(got[0], 1);
  EXPECT_EQ(search.removeOutsideBox(Eigen::Vector3f(5, 5, 5), Eigen::Vector3f(6, 6, 6)), 2u);
  EXPECT_EQ(search.size(), 0u);
  EXPECT_EQ(search.nearestKSearch(PointXYZ(1, 2, 3), 1, got, d), 0);
  EXPECT_EQ(search.radiusSearch(PointXYZ(1, 2, 3), 10.0, got, d), 0);
  // Refilled far away, in UTM-like coordinates: the grid fits the new points, which take the freed indices.
  Cloud far;
  far.push_back(PointXYZ(512345.5f, 5412345.0f, 80.0f));
  far.push_back(PointXYZ(512346.0f, 5412345.0f, 80.0f));
  EXPECT_EQ(search.addPoints(far, ids), 2u);
  EXPECT_EQ(ids, (pcl::Indices{0, 1}));
  EXPECT_EQ(search.getInputCloud()->size(), 2u);
  EXPECT_EQ(search.nearestKSearch(PointXYZ(512345.9f, 5412345.0f, 80.0f), 2, got, d), 2);
  EXPECT_EQ(got, (pcl::Indices{1, 0}));
  // UNAVAILABLE, as addPoints gives a skipped point, is passed over.
  EXPECT_EQ(search.removePoints(pcl::Indices{1, 1, pcl::UNAVAILABLE}), 1u);
  EXPECT_EQ(search.nearestKSearch(PointXYZ(1, 2, 3), 1, got, d), 1);
  EXPECT_EQ(got[0], 0);
}

TEST(SearchUpdates, BadInputGetsAnErrorAndChangesNothing) {
  auto cloud = std::make_shared<Cloud>();
  for (int i = 0; i < 50; ++i) cloud->push_back(PointXYZ(0.1f * float(i), 0, 0));
  Search search;
  search.setInputCloud(cloud);
  EXPECT_EQ(search.removePoints(pcl::Indices{3, 50}), 0u);  // 50 lies outside the cloud
  EXPECT_EQ(search.removePoints(pcl::Indices{3, -2}), 0u);
  EXPECT_EQ(search.removePoints(pcl::Indices{-1}), 0u);  // UNAVAILABLE: passed over
  EXPECT_EQ(search.size(), 50u);
  const float nan = kNaN;
  EXPECT_EQ(search.removePoints(Eigen::Vector3f(nan, 0, 0), Eigen::Vector3f(1, 1, 1)), 0u);
  EXPECT_EQ(search.removeOutsideBox(Eigen::Vector3f(1, 1, 1), Eigen::Vector3f(0, 0, 0)), 0u);  // min > max
  EXPECT_EQ(search.size(), 50u);
  pcl::Indices got;
  std::vector<float> d;
  EXPECT_EQ(search.nearestKSearch(PointXYZ(0, 0, 0), 0, got, d), 0);
  EXPECT_EQ(search.nearestKSearch(PointXYZ(0, 0, 0), -3, got, d), 0);
  EXPECT_EQ(search.radiusSearch(PointXYZ(0, 0, 0), -1.0, got, d), 0);
  EXPECT_EQ(search.radiusSearch(PointXYZ(0, 0, 0), std::nan(""), got, d), 0);
  EXPECT_TRUE(got.empty());
  // Removing a point twice counts it once.
  EXPECT_EQ(search.removePoints(pcl::Indices{7, 7}), 1u);
  EXPECT_EQ(search.removePoints(pcl::Indices{7}), 0u);
  EXPECT_EQ(search.size(), 49u);
}

TEST_P(SearchUpdatesOnScans, ACrowdedMapPicksItsCellsAnewAndAnswersAlike) {
  // Frames of one place pile up in the cells picked for the first: the grid is fitted again, exactly.
  const Cloud::Ptr room = pcl_fot_test::loadScan("room_scan1.pcd");
  Search grown;
  Cloud part[8];
  for (std::size_t i = 0; i < room->size(); ++i) part[i % 8].push_back((*room)[i]);
  grown.addPoints(part[0]);
  const double first_edge = grown.getResolution();
  for (int p = 1; p < 8; ++p) grown.addPoints(part[p]);
  EXPECT_LT(grown.getResolution(), first_edge);
  Search fresh;
  fresh.setInputCloud(grown.getInputCloud());
  pcl::Indices got, want;
  std::vector<float> dg, dw;
  for (std::size_t i = 0; i < room->size(); i += 97) {
    const PointXYZ q((*room)[i].x + 0.01f, (*room)[i].y, (*room)[i].z - 0.02f);
    ASSERT_EQ(grown.nearestKSearch(q, 5, got, dg), fresh.nearestKSearch(q, 5, want, dw));
    ASSERT_EQ(got, want);
    ASSERT_EQ(dg, dw);
  }
}

// Issue 47, the first defect: removed points stayed in getInputCloud() and in the index's table by index, so
// a window's memory grew with every point ever added. Only the API that predates the fix is used here.
TEST(SearchUpdates, AWindowCostsTheMemoryOfThePointsItHolds) {
  constexpr std::size_t kPerFrame = 2000, kWindow = 5;
  constexpr int kFrames = 400;
  std::mt19937 rng(47);
  // Frame f fills the slab x in [f, f + 1): a sensor moving along x. The window keeps the last 5 frames.
  const auto frame = [&](int f) {
    Cloud c;
    for (std::size_t i = 0; i < kPerFrame; ++i)
      c.push_back(PointXYZ(float(f) + float(rng() % 1000) / 1000.0f, float(rng() % 4000) / 1000.0f,
                           float(rng() % 4000) / 1000.0f));
    return c;
  };
  Search window;
  std::size_t bytes_early = 0;
  for (int f = 0; f < kFrames; ++f) {
    ASSERT_EQ(window.addPoints(frame(f)), kPerFrame);
    window.removeOutsideBox(Eigen::Vector3f(float(f) - float(kWindow) + 1.0f, -1.0f, -1.0f),
                            Eigen::Vector3f(float(f) + 1.0f, 5.0f, 5.0f));
    ASSERT_EQ(window.size(), std::min<std::size_t>(std::size_t(f) + 1, kWindow) * kPerFrame);
    if (f == 40) bytes_early = window.getPointIndex().getMemoryBytes();
  }
  // The cloud holds as many points as the window did at its fullest (a frame added, the oldest not yet
  // removed), not the 800,000 added; the index's memory stays as it was after 40 frames. Before the fix:
  // 800,000 points, and the table by index alone took 8 bytes for each.
  EXPECT_LE(window.getInputCloud()->size(), (kWindow + 1) * kPerFrame);
  EXPECT_LT(window.getPointIndex().getMemoryBytes(), 3 * bytes_early);
  // And it still answers as a new search of the points it holds.
  Search fresh;
  pcl::IndicesPtr held(new pcl::Indices);
  const Cloud& all = *window.getInputCloud();
  for (std::size_t i = 0; i < all.size(); ++i)
    if (all[i].x >= float(kFrames) - float(kWindow)) held->push_back(int(i));
  ASSERT_EQ(held->size(), window.size());
  fresh.setInputCloud(window.getInputCloud(), held);
  pcl::Indices got, want;
  std::vector<float> dg, dw;
  for (std::size_t i = 0; i < all.size(); i += 37) {
    ASSERT_EQ(window.nearestKSearch(all[i], 4, got, dg), fresh.nearestKSearch(all[i], 4, want, dw));
    ASSERT_EQ(got, want);
  }
}

// Issue 47, the second defect: addPoints(*getInputCloud()) appended the cloud to itself while reading it,
// then indexed the doubled cloud as the added points: twice the points, indices past the cloud's end.
TEST(SearchUpdates, TheSearchsOwnCloudCanBeAddedToIt) {
  auto cloud = std::make_shared<Cloud>();
  for (int i = 0; i < 100; ++i) cloud->push_back(PointXYZ(0.1f * float(i), 0.05f * float(i % 7), 0.0f));
  Search search;
  search.setInputCloud(cloud);
  ASSERT_EQ(search.addPoints(*cloud), 100u);  // the search's own cloud from here on: 200 points
  {
    const Cloud& own = *search.getInputCloud();  // a reference only: no snapshot is held
    EXPECT_EQ(search.addPoints(own), 200u);
  }
  EXPECT_EQ(search.addPoints(*search.getInputCloud()), 400u);
  const Cloud& all = *search.getInputCloud();
  ASSERT_EQ(all.size(), 800u);
  EXPECT_EQ(search.size(), 800u);
  for (std::size_t i = 0; i < all.size(); ++i) ASSERT_TRUE(sameXYZ(all[i], (*cloud)[i % 100])) << i;
  std::mt19937 rng(2);
  ASSERT_NO_FATAL_FAILURE(expectBruteForce(search, std::vector<bool>(all.size(), true), rng));
}

// Issue 47, the third defect: a cloud from getInputCloud() changed under its holder at the next addPoints
// (and was reallocated, under a reader on another thread: Concurrency.SnapshotsAreReadWhileTheSearchUpdates).
TEST(SearchUpdates, AHeldCloudIsASnapshot) {
  std::mt19937 rng(3);
  Search search(0.25);
  ASSERT_GT(search.addPoints(latticeBatch(rng, 200)), 0u);  // the search's own cloud from here on
  const Cloud::ConstPtr snapshot = search.getInputCloud();
  const Cloud before = *snapshot;
  search.removePoints(pcl::Indices{0, 1, 2, 3, 4, 5, 6, 7});
  search.addPoints(latticeBatch(rng, 50));
  search.removeOutsideBox(Eigen::Vector3f(-1, -1, -1), Eigen::Vector3f(1, 1, 1));
  search.addPoints(latticeBatch(rng, 80));
  EXPECT_TRUE(sameClouds(*snapshot, before));
  EXPECT_NE(search.getInputCloud(), snapshot);
  // With no snapshot held, an update writes the search's cloud in place: no copy.
  const Cloud* own = search.getInputCloud().get();
  search.addPoints(latticeBatch(rng, 30));
  search.removePoints(pcl::Indices{9});
  EXPECT_EQ(search.getInputCloud().get(), own);
  // A search of the snapshot answers for the points it held, whatever the other search does meanwhile.
  Search reader(0.25);
  reader.setInputCloud(snapshot);
  std::vector<bool> held(before.size());
  for (std::size_t i = 0; i < before.size(); ++i) held[i] = pcl::isFinite(before[i]);
  search.addPoints(latticeBatch(rng, 100));
  ASSERT_EQ(reader.getInputCloud()->size(), held.size());
  ASSERT_NO_FATAL_FAILURE(expectBruteForce(reader, held, rng));
}

TEST(SearchUpdates, RemovedIndicesGoToLaterPointsLowestFirst) {
  Search search(0.5);
  Cloud ten;
  for (int i = 0; i < 10; ++i) ten.push_back(PointXYZ(float(i), 0.0f, 0.0f));
  pcl::Indices ids, want(10);
  ASSERT_EQ(search.addPoints(ten, ids), 10u);
  std::iota(want.begin(), want.end(), 0);
  EXPECT_EQ(ids, want);
  EXPECT_EQ(search.removePoints(pcl::Indices{7, 3}), 2u);
  Cloud more;
  more.push_back(PointXYZ(100.0f, 0.0f, 0.0f));
  more.push_back(PointXYZ(kNaN, 0.0f, 0.0f));
  more.push_back(PointXYZ(101.0f, 0.0f, 0.0f));
  more.push_back(PointXYZ(102.0f, 0.0f, 0.0f));
  ASSERT_EQ(search.addPoints(more, ids), 3u);
  EXPECT_EQ(ids, (pcl::Indices{3, pcl::UNAVAILABLE, 7, 10}));
  const Cloud& all = *search.getInputCloud();
  ASSERT_EQ(all.size(), 11u);
  EXPECT_EQ(all[3].x, 100.0f);
  EXPECT_EQ(all[7].x, 101.0f);
  EXPECT_EQ(all[10].x, 102.0f);
  pcl::Indices got;
  std::vector<float> d;
  EXPECT_EQ(search.nearestKSearch(PointXYZ(101.2f, 0.0f, 0.0f), 2, got, d), 2);
  EXPECT_EQ(got, (pcl::Indices{7, 10}));
  EXPECT_EQ(search.nearestKSearch(PointXYZ(3.1f, 0.0f, 0.0f), 1, got, d), 1);
  EXPECT_EQ(got[0], 4);  // not 3: that is the point at x = 100 now
  // The batch's indices, UNAVAILABLE included, remove the batch.
  EXPECT_EQ(search.removePoints(ids), 3u);
  EXPECT_EQ(search.size(), 8u);
  // The points the input does not hold (not finite, or not among its indices) leave their indices free too;
  // the caller's cloud is not written.
  auto input = std::make_shared<Cloud>();
  for (int i = 0; i < 6; ++i) input->push_back(PointXYZ(float(i), 0.0f, 0.0f));
  (*input)[1].x = kNaN;
  search.setInputCloud(input, pcl::IndicesPtr(new pcl::Indices{0, 2, 4}));
  EXPECT_EQ(search.size(), 3u);
  ASSERT_EQ(search.addPoints(more, ids), 3u);
  EXPECT_EQ(ids, (pcl::Indices{1, pcl::UNAVAILABLE, 3, 5}));
  EXPECT_EQ(search.getInputCloud()->size(), 6u);
  EXPECT_TRUE(std::isnan((*input)[1].x));
  EXPECT_EQ((*input)[3].x, 3.0f);
  EXPECT_EQ((*search.getInputCloud())[3].x, 101.0f);
}

// Box removals walk the cells the box touches (or those it does not hold whole) and read points only on its
// faces: boxes on cell faces, through points, beyond the key range, and points beyond it too, against
// brute force.
TEST(SearchUpdates, BoxRemovalsEqualBruteForceAtTheFacesAndBeyondTheKeys) {
  const float big = std::numeric_limits<float>::max();
  const std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> boxes = {
      {Eigen::Vector3f(-0.5f, -0.5f, -0.5f), Eigen::Vector3f(0.5f, 0.5f, 0.5f)},     // faces on cell faces
      {Eigen::Vector3f(0.25f, 0.25f, 0.25f), Eigen::Vector3f(0.25f, 0.25f, 0.25f)},  // one point's place
      {Eigen::Vector3f(-0.3f, -2.0f, 0.1f), Eigen::Vector3f(0.7f, 2.0f, 0.6f)},
      {Eigen::Vector3f(-big, -big, -big), Eigen::Vector3f(0.0f, big, big)},  // beyond the keys
      {Eigen::Vector3f(-big, -big, -big), Eigen::Vector3f(big, big, big)},
      {Eigen::Vector3f(2e7f, -1.0f, -1.0f), Eigen::Vector3f(big, 1.0f, 1.0f)},  // only the far points
      {Eigen::Vector3f(5.0f, 5.0f, 5.0f), Eigen::Vector3f(6.0f, 6.0f, 6.0f)},   // none
  };
  for (const double resolution : {0.25, 0.1}) {
    for (std::size_t b = 0; b < boxes.size(); ++b) {
      for (const bool inside : {true, false}) {
        std::mt19937 rng(static_cast<unsigned>(b));
        Cloud cloud = latticeBatch(rng, 400);
        // Far points: the grid centres on the bulk, and the one 4e8 m away lies beyond its keys (an outlier).
        cloud.push_back(PointXYZ(3e7f, 0.0f, 0.0f));
        cloud.push_back(PointXYZ(-4e8f, 0.25f, 0.5f));
        Search search(resolution);
        pcl::Indices ids;
        search.addPoints(cloud, ids);
        const auto& [lo, hi] = boxes[b];
        std::vector<bool> held(search.getInputCloud()->size(), false);
        std::size_t expected = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
          if (ids[i] == pcl::UNAVAILABLE) continue;
          const Eigen::Vector3f p = cloud[i].getVector3fMap();
          const bool in = (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
          held[std::size_t(ids[i])] = in != inside;
          expected += in == inside;
        }
        ASSERT_EQ(inside ? search.removePoints(lo, hi) : search.removeOutsideBox(lo, hi), expected)
            << "box " << b << (inside ? " inside" : " outside") << ", cells of " << resolution << " m";
        ASSERT_EQ(search.size(), heldCount(held));
        ASSERT_NO_FATAL_FAILURE(expectBruteForce(search, held, rng)) << "box " << b;
      }
    }
  }
}
