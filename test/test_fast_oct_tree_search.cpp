// FastOctTreeSearch against FLANN and brute force: the same distances, to the bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <pcl/common/point_tests.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/search/brute_force.h>
#include <flann/flann.hpp>

#include <pcl_fot/pcl/search/fast_oct_tree_search.h>

#include "scan_data.h"

using pcl::PointXYZ;
using Cloud = pcl::PointCloud<PointXYZ>;
using Search = pcl::fot::search::FastOctTreeSearch<PointXYZ>;

namespace {

/** FLANN's exact kd-tree in the Manhattan metric, over the finite points; answers cloud indices. */
class FlannL1 {
 public:
  explicit FlannL1(const Cloud& cloud) {
    for (std::size_t i = 0; i < cloud.size(); ++i)
      if (pcl::isFinite(cloud[i])) {
        data_.insert(data_.end(), {cloud[i].x, cloud[i].y, cloud[i].z});
        ids_.push_back(int(i));
      }
    index_.reset(new flann::Index<flann::L1<float>>(flann::Matrix<float>(data_.data(), ids_.size(), 3),
                                                    flann::KDTreeSingleIndexParams(15)));
    index_->buildIndex();
  }
  float nearest(const PointXYZ& q) const {
    float query[3] = {q.x, q.y, q.z};
    int index;
    float dist;
    flann::Matrix<int> i(&index, 1, 1);
    flann::Matrix<float> d(&dist, 1, 1);
    index_->knnSearch(flann::Matrix<float>(query, 1, 3), i, d, 1, flann::SearchParams(-1, 0.0f));
    return dist;
  }

 private:
  std::vector<float> data_;
  std::vector<int> ids_;
  std::unique_ptr<flann::Index<flann::L1<float>>> index_;
};

/** Every finite query point of `queries` into `target`: 1-NN distances equal FLANN's in L2 and L1. */
void expectSameAsFlann(const std::string& target_name, const std::string& query_name, double res) {
  const Cloud::Ptr target = pcl_fot_test::loadScan(target_name);
  const Cloud::Ptr queries = pcl_fot_test::loadScan(query_name);
  pcl::KdTreeFLANN<PointXYZ> flann_l2;
  flann_l2.setInputCloud(target);
  FlannL1 flann_l1(*target);
  Search ours(res), ours_l1(res);
  ours.setInputCloud(target);
  ours_l1.setMetric(pcl::fot::Metric::Manhattan);
  ours_l1.setInputCloud(target);

  pcl::Indices a, b;
  std::vector<float> da, db;
  std::size_t compared = 0;
  for (const auto& q : *queries) {
    if (!pcl::isFinite(q)) continue;
    ASSERT_EQ(flann_l2.nearestKSearch(q, 1, a, da), 1);
    ASSERT_EQ(ours.nearestKSearch(q, 1, b, db), 1);
    ASSERT_EQ(da[0], db[0]) << "L2 1-NN of (" << q.x << ", " << q.y << ", " << q.z << ")";
    ASSERT_EQ(ours_l1.nearestKSearch(q, 1, b, db), 1);
    ASSERT_EQ(flann_l1.nearest(q), db[0]) << "L1 1-NN";
    ++compared;
  }
  EXPECT_GT(compared, queries->size() / 2) << "most points are finite, and each was compared";
}

}  // namespace

PCL_FOT_SCAN_TESTS(FastOctTreeSearchOnScans);

TEST_P(FastOctTreeSearchOnScans, SameDistancesAsFlannForEveryKinectPoint) {
  expectSameAsFlann("kinect_capture0001.pcd", "kinect_capture0002.pcd", 0.02);
}

TEST_P(FastOctTreeSearchOnScans, SameDistancesAsFlannOnTheRoomScans) {
  expectSameAsFlann("room_scan1.pcd", "room_scan2.pcd", 0.1);
}

/**
 * BruteForce sums the squares as Eigen does, dx² + (dy² + dz²), where FLANN and we sum (dx² + dy²) + dz²;
 * the last bit may differ. So its neighbours' distances are re-evaluated FLANN's way before comparing.
 */
std::vector<float> flannDistances(const Cloud& cloud, const PointXYZ& q, const pcl::Indices& idx) {
  std::vector<float> d;
  for (pcl::index_t i : idx) {
    const float dx = cloud[i].x - q.x, dy = cloud[i].y - q.y, dz = cloud[i].z - q.z;
    d.push_back(dx * dx + dy * dy + dz * dz);
  }
  std::sort(d.begin(), d.end());
  return d;
}

TEST_P(FastOctTreeSearchOnScans, KnnAndRadiusEqualBruteForce) {
  const Cloud::Ptr target = pcl_fot_test::loadScan("kinect_capture0003.pcd");
  const Cloud::Ptr queries = pcl_fot_test::loadScan("kinect_capture0001.pcd");
  pcl::search::BruteForce<PointXYZ> brute(true);
  brute.setInputCloud(target);
  for (double res : {0.005, 0.03}) {
    Search ours(res);
    ours.setInputCloud(target);
    pcl::Indices a, b;
    std::vector<float> da, db;
    std::size_t n = 0;
    for (std::size_t i = 0; i < queries->size(); i += queries->size() / 300) {
      const PointXYZ& q = (*queries)[i];
      if (!pcl::isFinite(q)) continue;
      ASSERT_EQ(brute.nearestKSearch(q, 12, a, da), ours.nearestKSearch(q, 12, b, db));
      ASSERT_EQ(flannDistances(*target, q, a), db) << "k-NN distances, nearest first";
      const double r = std::sqrt(0.5 * (double(db[10]) + double(db[11])));  // no point on the sphere
      brute.radiusSearch(q, r, a, da);
      ours.radiusSearch(q, r, b, db);
      ASSERT_EQ(flannDistances(*target, q, a), db) << "radius search";
      const std::vector<float> all = db;
      ASSERT_EQ(ours.radiusSearch(q, r, b, db, 5), 5) << "max_nn keeps the nearest";
      ASSERT_EQ(std::vector<float>(all.begin(), all.begin() + 5), db);
      ++n;
    }
    EXPECT_GT(n, 200u) << "most of the 300 sampled points are finite";
  }
}

TEST(FastOctTreeSearch, EveryKKeepsTheNearestInOrderWithTiesToTheSmallerIndex) {
  // A lattice in a shuffled order: many points tie. Small k keep their results sorted as they go, large k
  // in a heap; both must give the brute-force order, ties to the smaller index, for either metric. Cells of
  // 0.15 m hold a few points; cells of 0.8 m are crowded, their points split into boxes whose sides tie too.
  Cloud::Ptr cloud(new Cloud);
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j)
      for (int k = 0; k < 8; ++k) cloud->push_back(PointXYZ(0.1f * i, 0.1f * j, 0.1f * k));
  std::mt19937 rng(4);
  std::shuffle(cloud->begin(), cloud->end(), rng);
  for (double res : {0.15, 0.8})
    for (pcl::fot::Metric metric : {pcl::fot::Metric::Euclidean, pcl::fot::Metric::Manhattan}) {
      Search ours(res);
      ours.setMetric(metric);
      ours.setInputCloud(cloud);
      pcl::Indices b;
      std::vector<float> db;
      for (std::size_t i = 0; i < cloud->size(); i += 37) {
        PointXYZ q = (*cloud)[i];
        q.x += i % 2 ? 0.0f : 0.05f;  // on a lattice point, or halfway to the next
        std::vector<std::pair<float, pcl::index_t>> all;
        for (pcl::index_t j = 0; j < pcl::index_t(cloud->size()); ++j) {
          const float dx = (*cloud)[j].x - q.x, dy = (*cloud)[j].y - q.y, dz = (*cloud)[j].z - q.z;
          all.emplace_back(metric == pcl::fot::Metric::Euclidean
                               ? dx * dx + dy * dy + dz * dz
                               : std::fabs(dx) + std::fabs(dy) + std::fabs(dz),
                           j);
        }
        std::sort(all.begin(), all.end());
        for (int k : {10, 80, 81, 300, 1000}) {
          ASSERT_EQ(ours.nearestKSearch(q, k, b, db), k);
          for (int n = 0; n < k; ++n) {
            ASSERT_EQ(db[n], all[n].first) << "k " << k << ", result " << n;
            ASSERT_EQ(b[n], all[n].second) << "k " << k << ", result " << n;
          }
          // A radius search with max_nn keeps the same order.
          const double r = 0.45, bound = metric == pcl::fot::Metric::Euclidean ? r * r : r;
          const std::size_t within = std::size_t(
              std::count_if(all.begin(), all.end(), [&](const auto& a) { return double(a.first) <= bound; }));
          const std::size_t n = ours.radiusSearch(q, r, b, db, unsigned(k));
          ASSERT_EQ(n, std::min(within, std::size_t(k))) << "radius, max_nn " << k;
          for (std::size_t m = 0; m < n; ++m) ASSERT_EQ(b[m], all[m].second) << "radius, max_nn " << k;
        }
      }
    }
}

TEST(FastOctTreeSearch, APileOfEqualPointsGivesItsSmallestIndicesFirst) {
  // Sensors that write (0, 0, 0) for no return pile thousands of equal points in one cell. Its boxes split
  // them by index, and a search stops at the k smallest rather than scanning them all: check it keeps those.
  Cloud::Ptr cloud(new Cloud);
  std::vector<pcl::index_t> pile;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  for (int i = 0; i < 12000; ++i) {
    if (i % 3 == 1) pile.push_back(pcl::index_t(cloud->size()));
    cloud->push_back(i % 3 == 1 ? PointXYZ(0, 0, 0) : PointXYZ(u(rng), u(rng), u(rng)));
  }
  for (pcl::fot::Metric metric : {pcl::fot::Metric::Euclidean, pcl::fot::Metric::Manhattan})
    for (Search ours : {Search(), Search(0.5)}) {
      ours.setMetric(metric);
      ours.setInputCloud(cloud);
      pcl::Indices b;
      std::vector<float> db;
      for (int k : {1, 10, 80, 81, 500}) {
        ASSERT_EQ(ours.nearestKSearch(PointXYZ(0, 0, 0), k, b, db), k);
        EXPECT_EQ(b, pcl::Indices(pile.begin(), pile.begin() + k)) << "k " << k;
        EXPECT_EQ(db, std::vector<float>(std::size_t(k), 0.0f));
        ASSERT_EQ(ours.radiusSearch(PointXYZ(0, 0, 0), 1e-3, b, db, unsigned(k)), k);
        EXPECT_EQ(b, pcl::Indices(pile.begin(), pile.begin() + k)) << "radius, max_nn " << k;
      }
      ASSERT_EQ(ours.radiusSearch(PointXYZ(0, 0, 0), 1e-3, b, db), pile.size());
      EXPECT_EQ(b, pile) << "the whole pile, in index order";
      // From 1 m away, radius 1 m: the pile's box lies on the bound before any result is kept.
      const PointXYZ q(1, 0, 0);
      std::size_t within = 0;
      for (const PointXYZ& p : *cloud) {
        const float dx = p.x - q.x, dy = p.y - q.y, dz = p.z - q.z;
        within +=
            (metric == pcl::fot::Metric::Euclidean ? dx * dx + dy * dy + dz * dz
                                                   : std::fabs(dx) + std::fabs(dy) + std::fabs(dz)) <= 1.0f;
      }
      EXPECT_EQ(ours.radiusSearch(q, 1.0, b, db), within);
      EXPECT_EQ(ours.radiusSearch(q, 1.0, b, db, 4500), std::min<std::size_t>(within, 4500));
    }
}

TEST_P(FastOctTreeSearchOnScans, KeepsPclsSearchContract) {
  const Cloud::Ptr cloud = pcl_fot_test::loadScan("kinect_capture0002.pcd");  // organised: NaN points
  auto subset = std::make_shared<pcl::Indices>();
  for (pcl::index_t i = 0; i < pcl::index_t(cloud->size()); i += 3) subset->push_back(i);
  Search ours(0.02);
  ours.setInputCloud(cloud, subset);
  EXPECT_EQ(ours.getInputCloud(), cloud);
  EXPECT_EQ(ours.getIndices(), subset);
  EXPECT_EQ(ours.getName(), "FastOctTreeSearch");

  pcl::search::BruteForce<PointXYZ> brute;
  brute.setInputCloud(cloud, subset);
  pcl::Indices a, b;
  std::vector<float> da, db;
  for (std::size_t i = 1; i < cloud->size(); i += 1003) {
    const PointXYZ& q = (*cloud)[i];
    if (!pcl::isFinite(q)) {
      EXPECT_EQ(ours.nearestKSearch(q, 3, b, db), 0) << "a NaN query gets no results";
      // The placeholder PCL's registration reads unchecked: a point of the subset, infinitely far.
      ASSERT_EQ(b.size(), 1u);
      EXPECT_EQ(b[0] % 3, 0);
      EXPECT_TRUE(pcl::isFinite((*cloud)[b[0]]));
      EXPECT_EQ(db, std::vector<float>{std::numeric_limits<float>::infinity()});
      EXPECT_EQ(ours.radiusSearch(q, 0.5, b, db), 0);
      EXPECT_TRUE(b.empty() && db.empty());
      continue;
    }
    ASSERT_EQ(ours.nearestKSearch(q, 3, b, db), 3);
    brute.nearestKSearch(q, 3, a, da);
    ASSERT_EQ(flannDistances(*cloud, q, a), db);
    for (pcl::index_t idx : b) {
      EXPECT_EQ(idx % 3, 0) << "only indices of the subset, as cloud indices";
      EXPECT_TRUE(pcl::isFinite((*cloud)[idx])) << "never a NaN point";
    }
    EXPECT_TRUE(std::is_sorted(db.begin(), db.end()));
  }
  // k = 1 answers even far from the cloud.
  EXPECT_EQ(ours.nearestKSearch(PointXYZ(1e6f, -1e6f, 3e5f), 1, b, db), 1);
  // The (index) overload addresses the subset, as pcl::search::Search defines it.
  pcl::index_t at = 0;
  while (!pcl::isFinite((*cloud)[(*subset)[at]])) ++at;
  ASSERT_EQ(ours.nearestKSearch(at, 1, b, db), 1);
  EXPECT_EQ(db[0], 0.0f);
  EXPECT_EQ((*cloud)[b[0]].getVector3fMap(), (*cloud)[(*subset)[at]].getVector3fMap());
}

TEST_P(FastOctTreeSearchOnScans, RepeatedInputIsCheapAndChangesAreSeen) {
  Cloud::Ptr cloud(new Cloud(*pcl_fot_test::loadScan("room_scan1.pcd")));
  Search ours(0.1);
  ours.setInputCloud(cloud);
  const pcl::fot::PointIndex* index = &ours.getPointIndex();
  const std::size_t pool = index->tree().poolWords();
  ours.setInputCloud(cloud);  // ICP does this twice per align()
  pcl::Indices b;
  std::vector<float> db;
  ASSERT_EQ(ours.nearestKSearch((*cloud)[100], 1, b, db), 1);
  EXPECT_EQ(b[0], 100);
  EXPECT_EQ(index->tree().poolWords(), pool);
  (*cloud)[100].x += 5.0f;  // changed in place: the next setInputCloud rebuilds
  ours.setInputCloud(cloud);
  PointXYZ moved = (*cloud)[100];
  ASSERT_EQ(ours.nearestKSearch(moved, 1, b, db), 1);
  EXPECT_EQ(b[0], 100);
  EXPECT_EQ(db[0], 0.0f);
}

TEST(FastOctTreeSearch, EmptyAndDegenerateClouds) {
  Search ours(0.05);
  Cloud::Ptr empty(new Cloud);
  ours.setInputCloud(empty);
  pcl::Indices b;
  std::vector<float> db;
  EXPECT_EQ(ours.nearestKSearch(PointXYZ(0, 0, 0), 1, b, db), 0);
  Cloud::Ptr nans(new Cloud);
  nans->push_back(PointXYZ(std::nanf(""), 0, 0));
  ours.setInputCloud(nans);
  EXPECT_EQ(ours.nearestKSearch(PointXYZ(0, 0, 0), 1, b, db), 0);
  // Points thousands of kilometres apart: beyond any key range around a 5 cm grid, still found exactly.
  Cloud::Ptr far(new Cloud);
  far->push_back(PointXYZ(0, 0, 0));
  far->push_back(PointXYZ(3e7f, 0, 0));
  ours.setInputCloud(far);
  ASSERT_EQ(ours.nearestKSearch(PointXYZ(2.9e7f, 0, 0), 1, b, db), 1);
  EXPECT_EQ(b[0], 1);
  ASSERT_EQ(ours.nearestKSearch(PointXYZ(1, 0, 0), 2, b, db), 2);
  EXPECT_EQ(b[0], 0);
  // Beyond 2^29 cells either side of the centre: searched exhaustively, still counted and found.
  far->push_back(PointXYZ(-1e9f, 0, 0));
  far->push_back(PointXYZ(0, 1e9f, 0));
  ours.setInputCloud(far);
  EXPECT_EQ(ours.getPointIndex().size(), 4u);
  ASSERT_EQ(ours.nearestKSearch(PointXYZ(0, 9e8f, 0), 1, b, db), 1);
  EXPECT_EQ(b[0], 3);
  EXPECT_EQ(ours.nearestKSearch(PointXYZ(std::nanf(""), 0, 0), 1, b, db), 0);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_TRUE(b[0] >= 0 && b[0] < 4);
  EXPECT_THROW(Search(0.0), std::invalid_argument);
}

/** The points an occupied cell holds on average. */
double pointsPerCell(const Search& s) {
  return double(s.getPointIndex().size()) / double(s.getPointIndex().tree().getOccupiedCount());
}

/**
 * A 16-ring LiDAR 1.7 m above flat ground inside a round wall 40 m away: rings pointing down meet the
 * ground, the rest the wall, so returns are dense near the sensor and sparse far from it.
 */
Cloud::Ptr lidarInARing() {
  Cloud::Ptr cloud(new Cloud);
  for (int ring = 0; ring < 16; ++ring) {
    const double elevation = (-15.0 + 2.0 * ring) * M_PI / 180.0;
    const double to_ground = elevation < 0 ? 1.7 / std::sin(-elevation) : 1e9;
    const double range = std::min(to_ground, 40.0 / std::cos(elevation));
    for (int step = 0; step < 1800; ++step) {
      const double azimuth = step * M_PI / 900.0, across = range * std::cos(elevation);
      cloud->push_back(PointXYZ(float(across * std::cos(azimuth)), float(across * std::sin(azimuth)),
                                float(range * std::sin(elevation))));
    }
  }
  return cloud;
}

/**
 * A 64-ring spinning LiDAR, 1.8 m above flat ground, of 512,000 returns from 1 to 120 m: so many that the
 * edge is picked from a sample, and occupancy varies so much (thousands of points in a cell near the
 * sensor, one far away) that the sample alone picks cells several times too fine.
 */
Cloud::Ptr denseLidarSweep() {
  Cloud::Ptr cloud(new Cloud);
  std::mt19937 gen(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int ring = 0; ring < 64; ++ring)
    for (int step = 0; step < 8000; ++step) {
      const float elevation = float(M_PI / 180.0) * (-25.0f + 40.0f * float(ring) / 63.0f);
      const float azimuth = float(2.0 * M_PI) * float(step) / 8000.0f;
      float range = 1.0f + 119.0f * u(gen) * u(gen);
      if (elevation < 0) range = std::min(range, 1.8f / -std::sin(elevation));
      cloud->push_back(PointXYZ(range * std::cos(elevation) * std::cos(azimuth),
                                range * std::cos(elevation) * std::sin(azimuth),
                                range * std::sin(elevation)));
    }
  return cloud;
}

/** k-NN and radius searches on every `stride`-th finite point, moved a little, equal brute force's. */
void expectBruteForceAnswers(const Search& ours, const Cloud::Ptr& cloud, std::size_t stride,
                             const std::string& name) {
  pcl::search::BruteForce<PointXYZ> brute(true);
  brute.setInputCloud(cloud);
  pcl::Indices a, b;
  std::vector<float> da, db;
  for (std::size_t i = 0; i < cloud->size(); i += stride) {
    if (!pcl::isFinite((*cloud)[i])) continue;
    PointXYZ q = (*cloud)[i];
    q.x += 0.013f, q.y -= 0.021f;
    for (int k : {1, 10, 50}) {
      ASSERT_EQ(brute.nearestKSearch(q, k, a, da), ours.nearestKSearch(q, k, b, db)) << name;
      ASSERT_EQ(flannDistances(*cloud, q, a), db) << name << ": k-NN, k = " << k;
    }
    const double r = std::sqrt(0.5 * (double(db[8]) + double(db[9])));  // between the 9th and 10th
    if (db[8] == db[9] || !(r > 0.0)) continue;
    brute.radiusSearch(q, r, a, da);
    ours.radiusSearch(q, r, b, db);
    ASSERT_EQ(flannDistances(*cloud, q, a), db) << name << ": radius search";
  }
}

TEST_P(FastOctTreeSearchOnScans, TheDefaultPicksCellsOfAboutEightPointsForAnyCloud) {
  const std::vector<std::pair<std::string, Cloud::Ptr>> clouds = {
      {"LiDAR in a ring wall", lidarInARing()},
      {"dense LiDAR sweep", denseLidarSweep()},
      {"airborne terrain", pcl_fot_test::loadScan("terrain_samp11.pcd")},
      {"Kinect frame", pcl_fot_test::loadScan("kinect_capture0001.pcd")},
      {"room scan", pcl_fot_test::loadScan("room_scan1.pcd")}};
  for (const auto& [name, cloud] : clouds) {
    Search ours;  // made as a pcl::search::KdTree is, with no cell size
    ours.setInputCloud(cloud);
    ASSERT_TRUE(ours.getPointIndex().automatic());
    EXPECT_GE(pointsPerCell(ours), 4.0) << name << " at " << ours.getResolution() << " m";
    EXPECT_LE(pointsPerCell(ours), 64.0) << name << " at " << ours.getResolution() << " m";
    Search finer(ours.getResolution() / 2);  // the finest such edge: half of it holds fewer
    finer.setInputCloud(cloud);
    EXPECT_LT(pointsPerCell(finer), 8.0) << name;
    expectBruteForceAnswers(ours, cloud, cloud->size() / 400, name);
  }
}

TEST(FastOctTreeSearch, TheDefaultCopesWithDegenerateClouds) {
  const float big = 1.7e38f;
  std::mt19937 gen(3);
  std::uniform_real_distribution<float> spread(-1e30f, 1e30f), tiny(0.0f, 1e-30f);
  std::vector<std::pair<std::string, Cloud>> clouds(8);
  clouds[0].first = "one point";
  clouds[0].second.push_back(PointXYZ(1, 2, 3));
  clouds[1].first = "one place, 100 times";
  for (int i = 0; i < 100; ++i) clouds[1].second.push_back(PointXYZ(-4, 5, 6));
  clouds[2].first = "float's whole range";
  for (float x : {-big, big})
    for (float y : {-big, big}) clouds[2].second.push_back(PointXYZ(x, y, 0));
  clouds[3].first = "at float's limit";
  for (int i = 0; i < 20; ++i) clouds[3].second.push_back(PointXYZ(big + float(i) * 1e32f, 0, 0));
  clouds[4].first = "1e30 m wide";
  for (int i = 0; i < 200; ++i) clouds[4].second.push_back(PointXYZ(spread(gen), spread(gen), spread(gen)));
  clouds[5].first = "1e-30 m wide";
  for (int i = 0; i < 200; ++i) clouds[5].second.push_back(PointXYZ(tiny(gen), tiny(gen), tiny(gen)));
  clouds[6].first = "a cluster and far points";
  for (int i = 0; i < 500; ++i)
    clouds[6].second.push_back(PointXYZ(0.001f * float(i % 10), 0.001f * float(i / 10), 0));
  for (float f : {1e9f, -2e9f, 3e10f}) clouds[6].second.push_back(PointXYZ(f, -f, 0.5f * f));
  clouds[7].first = "a line with NaN and Inf points";
  for (int i = 0; i < 300; ++i)
    clouds[7].second.push_back(i % 3 == 0   ? PointXYZ(std::nanf(""), 0, 0)
                               : i % 3 == 1 ? PointXYZ(std::numeric_limits<float>::infinity(), 0, 0)
                                            : PointXYZ(0.01f * float(i), 0, 0));
  for (const auto& [name, points] : clouds) {
    Cloud::Ptr cloud(new Cloud(points));
    cloud->is_dense = false;  // else BruteForce takes the NaN points as any others
    Search ours;
    ours.setInputCloud(cloud);
    EXPECT_TRUE(ours.getResolution() > 0.0 && std::isfinite(ours.getResolution())) << name;
    pcl::Indices b;
    std::vector<float> db;
    // A fixed edge whose grid, centred on points near float's limit, would reach beyond it: centred on 0.
    Search coarse(5e29);
    ASSERT_NO_THROW(coarse.setInputCloud(cloud)) << name;
    if (points.size() >= 10) {
      expectBruteForceAnswers(ours, cloud, 1, name);
      expectBruteForceAnswers(coarse, cloud, 1, name + " in 5e29 m cells");
      continue;
    }
    ASSERT_EQ(ours.nearestKSearch(points[0], 3, b, db), std::min(3, int(points.size()))) << name;
    EXPECT_EQ(db[0], 0.0f) << name;
  }
  Search ours;
  ours.setInputCloud(Cloud::Ptr(new Cloud));
  pcl::Indices b;
  std::vector<float> db;
  EXPECT_EQ(ours.nearestKSearch(PointXYZ(0, 0, 0), 1, b, db), 0);
}

TEST(FastOctTreeSearch, StrayPointsFarAwayLeaveTheBulkInTheTree) {
  // A few stray returns far away, all on one side, as a stereo camera gives at near-zero disparity. They
  // must neither stretch the cells to their span nor push the bulk out of the keys' reach: either way a
  // search would scan most of the points.
  const Cloud::Ptr bulk = lidarInARing();
  Cloud::Ptr cloud(new Cloud);
  for (float f : {3e8f, 5e8f, 1e9f}) cloud->push_back(PointXYZ(f, 0.5f * f, 0));
  *cloud += *bulk;
  for (double res : {0.0, 0.05}) {  // 0: picked from the cloud
    const std::string name = res > 0 ? "0.05 m cells" : "automatic cells";
    Search alone = res > 0 ? Search(res) : Search(), ours = res > 0 ? Search(res) : Search();
    alone.setInputCloud(bulk);
    ours.setInputCloud(cloud);
    EXPECT_GE(ours.getResolution(), alone.getResolution() / 2) << name;
    EXPECT_LE(ours.getResolution(), alone.getResolution() * 2) << name;
    EXPECT_GT(ours.getPointIndex().tree().getOccupiedCount(),
              alone.getPointIndex().tree().getOccupiedCount() / 2)
        << name;
    expectBruteForceAnswers(ours, cloud, cloud->size() / 200, name);  // from a stray point on
  }
}

TEST(FastOctTreeSearch, PointsOnCellBoundariesAreFoundAtDistanceZero) {
  // A lattice of 0.25 m: many points lie on cell faces, where the query's cell (from the reciprocal of the
  // resolution) and the point's (from the division) may differ by one. At 2 cm, PointIndex's radius of 0
  // used to miss 1,560 of these 16,000 points, in either metric. Each point is there twice.
  Cloud::Ptr lattice(new Cloud);
  for (int copy = 0; copy < 2; ++copy)
    for (int i = -20; i < 20; ++i)
      for (int j = -20; j < 20; ++j)
        for (int k = 0; k < 10; ++k) lattice->push_back(PointXYZ(0.25f * i, 0.25f * j, 1.0f + 0.25f * k));
  const std::size_t n = lattice->size() / 2;
  pcl::search::KdTree<PointXYZ> flann;
  flann.setInputCloud(lattice);
  pcl::search::BruteForce<PointXYZ> brute;
  brute.setInputCloud(lattice);
  pcl::Indices none;
  std::vector<float> no_distances;
  ASSERT_EQ(flann.radiusSearch((*lattice)[0], 0.0, none, no_distances), 0) << "PCL's rule for a radius of 0";
  ASSERT_EQ(brute.radiusSearch((*lattice)[0], 0.0, none, no_distances), 0) << "PCL's rule for a radius of 0";
  for (double res : {0.02, 0.05, 0.01}) {
    for (auto metric : {pcl::fot::Metric::Euclidean, pcl::fot::Metric::Manhattan}) {
      Search ours(res);
      ours.setMetric(metric);
      ours.setInputCloud(lattice);
      pcl::Indices b;
      std::vector<float> db;
      for (std::size_t i = 0; i < n; ++i) {
        const float q[3] = {(*lattice)[i].x, (*lattice)[i].y, (*lattice)[i].z};
        std::vector<std::int32_t> found;
        ASSERT_EQ(ours.getPointIndex().radiusSearch(q, 0.0, metric, found, db), 2u)
            << "point " << i << " at res " << res;
        EXPECT_EQ(found, (std::vector<std::int32_t>{std::int32_t(i), std::int32_t(i + n)}));
        // PCL's searches find nothing within a radius of 0, and so does the drop-in.
        EXPECT_EQ(ours.radiusSearch((*lattice)[i], 0.0, b, db), 0);
        EXPECT_TRUE(b.empty() && db.empty());
        // The copy's k = 1: a tie at distance 0, which goes to the smaller index.
        ASSERT_EQ(ours.nearestKSearch((*lattice)[i + n], 1, b, db), 1);
        ASSERT_EQ(b[0], pcl::index_t(i)) << "point " << i << " at res " << res;
      }
    }
  }
}

TEST(FastOctTreeSearch, AnswersAsKdTreeForAnyIndicesRadiusAndMaxNn) {
  // A lattice, so that many distances tie; an index subset with repeats and NaN and Inf points in it.
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> step(-8, 8);
  Cloud::Ptr cloud(new Cloud);
  for (int i = 0; i < 200; ++i)
    cloud->push_back(PointXYZ(step(rng) * 0.05f, step(rng) * 0.05f, step(rng) * 0.05f));
  (*cloud)[7].x = std::nanf("");
  (*cloud)[9].y = std::numeric_limits<float>::infinity();
  auto subset = std::make_shared<pcl::Indices>();
  for (pcl::index_t i = 0; i < 200; i += 2) subset->push_back(i);
  for (pcl::index_t i : {4, 4, 7, 9, 199}) subset->push_back(i);
  for (bool sorted : {true, false}) {
    pcl::search::KdTree<PointXYZ> flann(sorted);
    Search ours(0.05, sorted);
    flann.setInputCloud(cloud, subset);
    ours.setInputCloud(cloud, subset);
    pcl::Indices a, b;
    std::vector<float> da, db;
    for (const PointXYZ& q : *cloud) {
      if (!pcl::isFinite(q)) continue;
      for (int k : {1, 3, 10, 150, 500}) {
        ASSERT_EQ(flann.nearestKSearch(q, k, a, da), ours.nearestKSearch(q, k, b, db)) << "k " << k;
        ASSERT_EQ(da, db) << "k " << k;  // ties may list other indices, at the same distances
      }
      // A negative radius finds nothing, as in BruteForce; KdTreeFLANN squares it.
      ASSERT_EQ(ours.radiusSearch(q, -1.0, b, db), 0);
      for (double r : {0.0, 0.05, 0.1, 0.3})
        for (unsigned max_nn : {0u, 1u, 5u}) {
          ASSERT_EQ(flann.radiusSearch(q, r, a, da, max_nn), ours.radiusSearch(q, r, b, db, max_nn))
              << "radius " << r << ", max_nn " << max_nn;
          std::sort(da.begin(), da.end());
          ASSERT_EQ(da, db) << "radius " << r << ", max_nn " << max_nn;
        }
    }
  }
}
