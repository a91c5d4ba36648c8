// FastOctTreeSearch updated in place: after any sequence of additions and removals, its answers equal brute
// force over the points held, and a new search of them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
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
  const Cloud& cloud = *search.getInputCloud();
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

}  // namespace

TEST(SearchUpdates, RandomSequencesEqualBruteForce) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    std::mt19937 rng(seed);
    // Half the runs start from setInputCloud, half from nothing; half pick their cell edge.
    Search search = seed % 2 ? Search() : Search(0.3);
    std::vector<bool> held;
    const auto note = [&](const Cloud& added) {
      for (const auto& p : added) held.push_back(pcl::isFinite(p));
    };
    if (seed % 3 != 0) {
      auto first = std::make_shared<Cloud>(latticeBatch(rng, 300));
      search.setInputCloud(first);
      note(*first);
    }
    for (int step = 0; step < 40; ++step) {
      const Cloud& cloud = search.getInputCloud() ? *search.getInputCloud() : Cloud();
      switch (rng() % 5) {
        case 0:
        case 1: {
          const Cloud batch = latticeBatch(rng, rng() % 120);
          std::size_t finite = 0;
          for (const auto& p : batch) finite += pcl::isFinite(p);
          ASSERT_EQ(search.addPoints(batch), finite);
          note(batch);
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
  updated.addPoints(*other);
  updated.removePoints(mid - Eigen::Vector3f::Constant(0.5f), mid + Eigen::Vector3f::Constant(0.5f));

  const Cloud& all = *updated.getInputCloud();
  ASSERT_EQ(all.size(), room->size() + other->size());
  pcl::IndicesPtr survivors(new pcl::Indices);
  pcl::Indices got, want;
  std::vector<float> dg, dw;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (!pcl::isFinite(all[i])) continue;
    const Eigen::Vector3f p = all[i].getVector3fMap();
    const bool cut = (p.array() >= (mid.array() - 0.5f)).all() && (p.array() <= (mid.array() + 0.5f)).all();
    const bool far = i < room->size() && p.x() > mid.x();
    if (!cut && !far) survivors->push_back(int(i));
  }
  ASSERT_EQ(survivors->size(), updated.size());
  Search fresh;
  fresh.setInputCloud(updated.getInputCloud(), survivors);
  for (std::size_t i = 0; i < all.size(); i += 11) {
    for (int k : {1, 10}) {
      ASSERT_EQ(updated.nearestKSearch(all[i], k, got, dg), fresh.nearestKSearch(all[i], k, want, dw));
      ASSERT_EQ(got, want);
      ASSERT_EQ(dg, dw);
    }
    ASSERT_EQ(updated.radiusSearch(all[i], 0.01, got, dg), fresh.radiusSearch(all[i], 0.01, want, dw));
    ASSERT_EQ(got, want);
  }
  // PCL's index-based queries reach the added points.
  const int added = int(room->size()) + 3;
  updated.nearestKSearch(added, 1, got, dg);
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
  EXPECT_EQ(search.addPoints(batch), 2u);  // no input cloud before: the additions are the cloud
  EXPECT_EQ(search.getSkippedCount(), 1u);
  EXPECT_EQ(search.nearestKSearch(PointXYZ(1, 2, 3.4f), 1, got, d), 1);
  EXPECT_EQ(got[0], 2);
  EXPECT_EQ(search.removeOutsideBox(Eigen::Vector3f(5, 5, 5), Eigen::Vector3f(6, 6, 6)), 2u);
  EXPECT_EQ(search.size(), 0u);
  EXPECT_EQ(search.nearestKSearch(PointXYZ(1, 2, 3), 1, got, d), 0);
  EXPECT_EQ(search.radiusSearch(PointXYZ(1, 2, 3), 10.0, got, d), 0);
  // Refilled far away, in UTM-like coordinates: the grid fits the new points, the indices go on.
  Cloud far;
  far.push_back(PointXYZ(512345.5f, 5412345.0f, 80.0f));
  far.push_back(PointXYZ(512346.0f, 5412345.0f, 80.0f));
  EXPECT_EQ(search.addPoints(far), 2u);
  EXPECT_EQ(search.nearestKSearch(PointXYZ(512345.9f, 5412345.0f, 80.0f), 2, got, d), 2);
  EXPECT_EQ(got, (pcl::Indices{4, 3}));
  EXPECT_EQ(search.removePoints(pcl::Indices{0, 1, 2, 4}), 1u);
  EXPECT_EQ(search.nearestKSearch(PointXYZ(1, 2, 3), 1, got, d), 1);
  EXPECT_EQ(got[0], 3);
}

TEST(SearchUpdates, BadInputGetsAnErrorAndChangesNothing) {
  auto cloud = std::make_shared<Cloud>();
  for (int i = 0; i < 50; ++i) cloud->push_back(PointXYZ(0.1f * float(i), 0, 0));
  Search search;
  search.setInputCloud(cloud);
  EXPECT_EQ(search.removePoints(pcl::Indices{3, 50}), 0u);  // 50 lies outside the cloud
  EXPECT_EQ(search.removePoints(pcl::Indices{-1}), 0u);
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
