// pcl::fot::OctreePointCloudSearch answers every search as pcl::octree::OctreePointCloudSearch does, call
// for call: on random clouds, on the real scans (NaN points included), on crowded voxels and ties.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <pcl/common/point_tests.h>  // PCL 1.13's occupancy header uses isFinite without including it
#include <pcl/octree/octree_pointcloud_occupancy.h>
#include <pcl/octree/octree_search.h>

#include <pcl_fot/pcl/octree/octree_point_cloud_search.h>

#include "scan_data.h"

using pcl::Indices;
using pcl::PointXYZ;
using Cloud = pcl::PointCloud<PointXYZ>;
using Reference = pcl::octree::OctreePointCloudSearch<PointXYZ>;
using Ours = pcl::fot::OctreePointCloudSearch<PointXYZ>;

namespace {

float octreeDistance(const PointXYZ& a, const PointXYZ& b) {
  return (a.getVector3fMap() - b.getVector3fMap()).squaredNorm();
}

/**
 * k-NN answers agree: the same distances, bit for bit, and the same indices, except that points at one
 * distance may come in another order (PCL leaves ties unordered), and the last tied group, cut at k, may hold
 * other points at that same distance.
 */
void expectSameNearest(const Cloud& cloud, const PointXYZ& q, const Indices& ri, const std::vector<float>& rd,
                       const Indices& oi, const std::vector<float>& od) {
  ASSERT_EQ(ri.size(), oi.size());
  ASSERT_EQ(rd, od);
  for (std::size_t a = 0; a < ri.size();) {
    std::size_t b = a;
    while (b < ri.size() && rd[b] == rd[a]) ++b;
    if (b < ri.size()) {
      Indices r(ri.begin() + a, ri.begin() + b), o(oi.begin() + a, oi.begin() + b);
      std::sort(r.begin(), r.end());
      std::sort(o.begin(), o.end());
      ASSERT_EQ(r, o) << "points at distance " << rd[a];
    } else {
      for (std::size_t i = a; i < b; ++i) ASSERT_EQ(octreeDistance(cloud[oi[i]], q), rd[a]);
    }
    a = b;
  }
}

/** Whether `sub` appears in `seq` in the same order. */
bool isSubsequence(const Indices& sub, const Indices& seq) {
  auto at = seq.begin();
  for (const auto i : sub) {
    at = std::find(at, seq.end(), i);
    if (at == seq.end()) return false;
    ++at;
  }
  return true;
}

/** Brute force: the k nearest by pcl::octree's distance, ties to the smaller index. */
void bruteNearest(const Cloud& cloud, const PointXYZ& q, std::size_t k, Indices& indices,
                  std::vector<float>& distances) {
  std::vector<std::pair<float, pcl::index_t>> all;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (pcl::isFinite(cloud[i])) all.emplace_back(octreeDistance(cloud[i], q), pcl::index_t(i));
  std::sort(all.begin(), all.end());
  all.resize(std::min(k, all.size()));
  indices.clear();
  distances.clear();
  for (const auto& [d, i] : all) {
    indices.push_back(i);
    distances.push_back(d);
  }
}

struct Octrees {
  Reference ref;
  Ours ours;
  Octrees(const Cloud::ConstPtr& cloud, double res, std::size_t max_per_leaf) : ref(res), ours(res) {
    pcl_fot_test::fillBoth(ref, ours, cloud, max_per_leaf);
  }
};

/**
 * Every search of PCL's, at each query: the same answers in the same order. Where PCL's float voxel centres
 * are too coarse for its pruning (`pcl_exact` false: coordinates near 1e6), ours are the brute-force answers
 * and PCL's are the same or miss points, in the same order.
 */
void expectSameSearches(const Cloud::ConstPtr& cloud, double res, std::size_t max_per_leaf,
                        const std::vector<PointXYZ>& queries, bool pcl_exact = true) {
  Octrees t(cloud, res, max_per_leaf);
  ASSERT_EQ(t.ref.getLeafCount(), t.ours.getLeafCount());
  ASSERT_EQ(t.ref.getBranchCount(), t.ours.getBranchCount());
  // The leaves, depth first, with their points in order.
  auto r = t.ref.leaf_depth_begin();
  auto o = t.ours.leaf_depth_begin();
  for (; r != t.ref.leaf_depth_end(); ++r, ++o) {
    ASSERT_TRUE(o != t.ours.leaf_depth_end());
    ASSERT_EQ(r.getCurrentOctreeKey(), o.getCurrentOctreeKey());
    ASSERT_EQ(r.getCurrentOctreeDepth(), o.getCurrentOctreeDepth());
    ASSERT_EQ(r.getLeafContainer().getPointIndicesVector(), o.getLeafContainer().getPointIndicesVector());
  }
  EXPECT_TRUE(o == t.ours.leaf_depth_end());

  double lo[3], hi[3];
  t.ref.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  Indices ri, oi;
  std::vector<float> rd, od;
  for (const PointXYZ& q : queries) {
    SCOPED_TRACE(::testing::Message() << "query (" << q.x << ", " << q.y << ", " << q.z << ")");
    ri.clear();
    oi.clear();
    const bool inside =
        q.x >= lo[0] && q.y >= lo[1] && q.z >= lo[2] && q.x < hi[0] && q.y < hi[1] && q.z < hi[2];
    if (inside) {
      ASSERT_EQ(t.ref.voxelSearch(q, ri), t.ours.voxelSearch(q, oi));
      ASSERT_EQ(ri, oi);
    } else {
      ASSERT_FALSE(t.ours.voxelSearch(q, oi)) << "PCL asserts here";
    }
    for (const pcl::uindex_t k : {1u, 7u, 40u}) {
      t.ref.nearestKSearch(q, k, ri, rd);
      t.ours.nearestKSearch(q, k, oi, od);
      if (pcl_exact) {
        expectSameNearest(*cloud, q, ri, rd, oi, od);
      } else {
        Indices bi;
        std::vector<float> bd;
        bruteNearest(*cloud, q, k, bi, bd);
        expectSameNearest(*cloud, q, bi, bd, oi, od);
        ASSERT_EQ(rd.size(), od.size());
        for (std::size_t i = 0; i < rd.size(); ++i) ASSERT_GE(rd[i], od[i]) << "PCL can only miss points";
      }
    }
    pcl::index_t r_index = -1, o_index = -1;
    float r_distance = -1, o_distance = -1;
    t.ref.approxNearestSearch(q, r_index, r_distance);
    t.ours.approxNearestSearch(q, o_index, o_distance);
    ASSERT_EQ(r_index, o_index);
    ASSERT_EQ(r_distance, o_distance);
    for (const double radius : {res * 0.7, res * 3.0}) {
      for (const pcl::uindex_t max_nn : {0u, 5u}) {
        const std::size_t r_found = t.ref.radiusSearch(q, radius, ri, rd, max_nn);
        const std::size_t o_found = t.ours.radiusSearch(q, radius, oi, od, max_nn);
        ASSERT_EQ(r_found, ri.size());
        ASSERT_EQ(o_found, oi.size());
        if (pcl_exact) {
          ASSERT_EQ(ri, oi) << "radius " << radius << ", max_nn " << max_nn;
          ASSERT_EQ(rd, od);
        } else if (max_nn == 0) {
          ASSERT_TRUE(isSubsequence(ri, oi)) << "radius " << radius;
          std::size_t within = 0;
          for (const PointXYZ& p : *cloud)
            within += pcl::isFinite(p) && octreeDistance(p, q) <= radius * radius;
          ASSERT_EQ(oi.size(), within) << "radius " << radius;
        }
      }
    }
    const Eigen::Vector3f half(float(res) * 2.5f, float(res) * 1.5f, float(res) * 2.0f);
    const Eigen::Vector3f lo = q.getVector3fMap() - half, hi = q.getVector3fMap() + half;
    t.ref.boxSearch(lo, hi, ri);
    t.ours.boxSearch(lo, hi, oi);
    if (pcl_exact) {
      ASSERT_EQ(ri, oi);
    } else {
      ASSERT_TRUE(isSubsequence(ri, oi));
      std::size_t inside_box = 0;
      for (const PointXYZ& p : *cloud)
        inside_box += pcl::isFinite(p) && (p.getVector3fMap().array() >= lo.array()).all() &&
                      (p.getVector3fMap().array() <= hi.array()).all();
      ASSERT_EQ(oi.size(), inside_box);
    }
  }
}

/** Queries near the cloud's points (jittered by up to two voxels), and a few far away. */
std::vector<PointXYZ> queriesFor(const Cloud& cloud, double res, std::size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-2.0f * float(res), 2.0f * float(res));
  std::uniform_int_distribution<std::size_t> pick(0, cloud.size() - 1);
  std::vector<PointXYZ> queries;
  while (queries.size() < count) {
    const PointXYZ& p = cloud[pick(rng)];
    if (!pcl::isFinite(p)) continue;
    queries.emplace_back(p.x + jitter(rng), p.y + jitter(rng), p.z + jitter(rng));
  }
  queries.emplace_back(1e3f, -2e3f, 5e2f);
  queries.emplace_back(-40.0f, 0.0f, 0.0f);
  return queries;
}

struct ScanCase {
  std::string scan;
  double resolution;
  std::size_t max_per_leaf;
  bool pcl_exact;  // false where PCL's float voxel centres are too coarse (UTM coordinates)
  pcl_fot_test::ScanSet set;
};

void PrintTo(const ScanCase& c, std::ostream* os) {
  *os << c.scan << " at " << c.resolution << " m, dynamic depth " << c.max_per_leaf;
}

class OctreeSearchOnScans : public ::testing::TestWithParam<ScanCase> {
  void SetUp() override {
    if (!pcl_fot_test::useScans(GetParam().set)) GTEST_SKIP() << pcl_fot_test::missingScansMessage();
  }
};

std::vector<ScanCase> scanCases(pcl_fot_test::ScanSet set) {
  return {{"kinect_capture0001.pcd", 0.02, 0, true, set},
          {"room_scan1.pcd", 0.05, 0, true, set},
          {"room_scan1.pcd", 0.01, 8, true, set},
          {"terrain_samp11.pcd", 0.5, 0, false, set}};
}

std::string scanCaseName(const ::testing::TestParamInfo<ScanCase>& info) {
  return info.param.scan.substr(0, info.param.scan.find('.')) + (info.param.max_per_leaf ? "_dynamic" : "") +
         "_" + std::to_string(info.index);
}

}  // namespace

TEST_P(OctreeSearchOnScans, SameAnswersAsPcl) {
  const auto cloud = pcl_fot_test::loadScan(GetParam().scan);
  expectSameSearches(cloud, GetParam().resolution, GetParam().max_per_leaf,
                     queriesFor(*cloud, GetParam().resolution, 150, 5), GetParam().pcl_exact);
}

INSTANTIATE_TEST_SUITE_P(Synthetic, OctreeSearchOnScans,
                         ::testing::ValuesIn(scanCases(pcl_fot_test::ScanSet::Synthetic)), scanCaseName);
INSTANTIATE_TEST_SUITE_P(Real, OctreeSearchOnScans,
                         ::testing::ValuesIn(scanCases(pcl_fot_test::ScanSet::Real)), scanCaseName);

TEST(OctreeSearchAgreement, RandomClouds) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    const auto cloud = pcl_fot_test::randomCloud(2000, 10.0f, seed);
    for (const std::size_t max_per_leaf : {0, 5})
      expectSameSearches(cloud, 0.3, max_per_leaf, queriesFor(*cloud, 0.3, 60, seed));
  }
}

TEST(OctreeSearchAgreement, CrowdedVoxelsDuplicatesAndTies) {
  // Points on a lattice of 1 cm (equal distances everywhere), each one three times, in voxels of 20 cm.
  Cloud::Ptr cloud(new Cloud);
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 12; ++y)
      for (int z = 0; z < 12; ++z)
        for (int copy = 0; copy < 3; ++copy) cloud->emplace_back(0.01f * x, 0.01f * y, 0.01f * z);
  std::vector<PointXYZ> queries;
  for (const PointXYZ& p : *cloud)
    if (queries.size() < 120 && (&p - &(*cloud)[0]) % 37 == 0) queries.push_back(p);
  queries.emplace_back(0.055f, 0.055f, 0.055f);  // equidistant from eight lattice points
  expectSameSearches(cloud, 0.2, 0, queries);
  expectSameSearches(cloud, 0.005, 0, queries);
  expectSameSearches(cloud, 0.005, 4, queries);
}

PCL_FOT_SCAN_TESTS(OctreeSearchAgreementOnScans);

TEST_P(OctreeSearchAgreementOnScans, RayIndicesAreTheVoxelsPointsInRayOrder) {
  const auto cloud = pcl_fot_test::loadScan("room_scan1.pcd");
  Octrees t(cloud, 0.05, 0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> jitter(-1.0f, 1.0f);
  std::size_t compared = 0;
  for (std::size_t i = 0; i < cloud->size(); i += 211) {
    const Eigen::Vector3f origin(jitter(rng), jitter(rng), 0.5f * jitter(rng));
    const Eigen::Vector3f direction = (*cloud)[i].getVector3fMap() - origin;
    for (const pcl::uindex_t max_count : {0u, 1u, 3u}) {
      Reference::AlignedPointTVector rc;
      Ours::AlignedPointTVector oc;
      Indices ri, oi;
      t.ref.getIntersectedVoxelCenters(origin, direction, rc, max_count);
      t.ours.getIntersectedVoxelCenters(origin, direction, oc, max_count);
      t.ref.getIntersectedVoxelIndices(origin, direction, ri, max_count);
      t.ours.getIntersectedVoxelIndices(origin, direction, oi, max_count);
      // Ours lists each voxel's points, voxel by voxel along the ray.
      Indices expected;
      for (const PointXYZ& c : oc) t.ours.voxelSearch(c, expected);
      ASSERT_EQ(oi, expected);
      // Rays that graze a voxel's edge may differ (test_octree_point_cloud checks those); the rest agree.
      const bool same_voxels =
          rc.size() == oc.size() &&
          std::equal(rc.begin(), rc.end(), oc.begin(), [](const PointXYZ& a, const PointXYZ& b) {
            return a.x == b.x && a.y == b.y && a.z == b.z;
          });
      if (same_voxels) {
        ASSERT_EQ(ri, oi);
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 3 * (cloud->size() / 211) * 9 / 10);
}

TEST(OctreeSearchAgreement, BadInputGetsAnEmptyAnswer) {
  Ours ours(0.1);
  Indices indices{7};
  std::vector<float> distances{1.0f};
  // Before any input.
  EXPECT_EQ(ours.nearestKSearch(PointXYZ(0, 0, 0), 3, indices, distances), 0u);
  EXPECT_TRUE(indices.empty() && distances.empty());
  EXPECT_EQ(ours.radiusSearch(PointXYZ(0, 0, 0), 1.0, indices, distances), 0u);
  EXPECT_FALSE(ours.voxelSearch(PointXYZ(0, 0, 0), indices));
  EXPECT_EQ(ours.boxSearch(Eigen::Vector3f::Zero(), Eigen::Vector3f::Ones(), indices), 0u);
  pcl::index_t index = -5;
  float distance = -5;
  ours.approxNearestSearch(PointXYZ(0, 0, 0), index, distance);
  EXPECT_EQ(index, -5);

  const auto cloud = pcl_fot_test::randomCloud(100, 1.0f, 9);
  cloud->emplace_back(std::nanf(""), 0.0f, 0.0f);
  ours.setInputCloud(cloud);
  ours.addPointsFromInputCloud();
  Indices all;
  for (auto it = ours.leaf_depth_begin(); it != ours.leaf_depth_end(); ++it)
    it.getLeafContainer().getPointIndices(all);
  EXPECT_EQ(all.size(), 100u) << "the NaN point is left out";
  const PointXYZ nan_query(std::nanf(""), 0.0f, 0.0f);
  EXPECT_EQ(ours.nearestKSearch(nan_query, 3, indices, distances), 0u);
  EXPECT_EQ(ours.nearestKSearch(PointXYZ(0.5f, 0.5f, 0.5f), 0, indices, distances), 0u);
  EXPECT_EQ(ours.radiusSearch(PointXYZ(0.5f, 0.5f, 0.5f), -1.0, indices, distances), 0u);
  EXPECT_EQ(ours.radiusSearch(PointXYZ(0.5f, 0.5f, 0.5f), std::nan(""), indices, distances), 0u);
  EXPECT_EQ(ours.nearestKSearch(pcl::uindex_t(500), 3, indices, distances), 0u)
      << "an index beyond the cloud";
  EXPECT_EQ(ours.nearestKSearch(pcl::uindex_t(100), 3, indices, distances), 0u) << "the NaN point as query";
  EXPECT_EQ(ours.boxSearch(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(std::nanf(""), 1, 1), indices), 0u);
  // And it still answers.
  EXPECT_EQ(ours.nearestKSearch(PointXYZ(0.5f, 0.5f, 0.5f), 3, indices, distances), 3u);
  EXPECT_EQ(ours.radiusSearch(PointXYZ(0.5f, 0.5f, 0.5f), 10.0, indices, distances), 100u);
}

namespace {

/** An octree's nodes in depth-first order: each one's key, depth and child pattern. */
template <typename Octree>
std::vector<std::tuple<pcl::uindex_t, pcl::uindex_t, pcl::uindex_t, pcl::uindex_t, char>> nodesOf(
    const Octree& octree) {
  std::vector<std::tuple<pcl::uindex_t, pcl::uindex_t, pcl::uindex_t, pcl::uindex_t, char>> nodes;
  for (auto it = octree.begin(); it != octree.end(); ++it) {
    const auto& k = it.getCurrentOctreeKey();
    nodes.emplace_back(k.x, k.y, k.z, it.getCurrentOctreeDepth(), it.getNodeConfiguration());
  }
  return nodes;
}

}  // namespace

// The k-NN index and the branch index follow single adds and voxel deletions in place: after every step the
// answers equal those of a copy of the octree (a copy builds its indices afresh), and pcl::octree's after the
// same steps.
TEST(OctreeSearchAgreement, InterleavedAddsDeletionsAndSearchesEqualAFreshBuild) {
  for (const std::size_t max_per_leaf : {0, 4}) {
    Cloud::Ptr cloud(new Cloud), ref_cloud(new Cloud);  // each octree appends to its own
    Ours ours(0.25);
    Reference ref(0.25);
    ours.setInputCloud(cloud);
    ref.setInputCloud(ref_cloud);
    if (max_per_leaf) {
      ours.enableDynamicDepth(max_per_leaf);
      ref.enableDynamicDepth(max_per_leaf);
    }
    std::mt19937 rng(17 + unsigned(max_per_leaf));
    std::uniform_real_distribution<float> coordinate(-2.0f, 2.0f);
    for (int step = 0; step < 400; ++step) {
      const PointXYZ p(coordinate(rng), coordinate(rng), 0.5f * coordinate(rng));
      if (step % 9 == 8) {
        const PointXYZ victim = (*cloud)[rng() % cloud->size()];
        ours.deleteVoxelAtPoint(victim);
        ref.deleteVoxelAtPoint(victim);
      } else {
        ours.addPointToCloud(p, cloud);
        ref.addPointToCloud(p, ref_cloud);
      }
      if (ours.getLeafCount() == 0) continue;
      const Ours fresh(ours);
      ASSERT_EQ(ours.getBranchCount(), ref.getBranchCount()) << "step " << step;
      ASSERT_EQ(nodesOf(ours), nodesOf(fresh)) << "step " << step;
      for (const std::size_t k : {1, 5}) {
        Indices oi, fi, ri;
        std::vector<float> od, fd, rd;
        ours.nearestKSearch(p, pcl::uindex_t(k), oi, od);
        fresh.nearestKSearch(p, pcl::uindex_t(k), fi, fd);
        ref.nearestKSearch(p, pcl::uindex_t(k), ri, rd);
        ASSERT_EQ(oi, fi) << "step " << step << ", k = " << k;
        ASSERT_EQ(od, fd) << "step " << step << ", k = " << k;
        expectSameNearest(*cloud, p, ri, rd, oi, od);
      }
      pcl::index_t oa, fa, ra;
      float oad, fad, rad;
      ours.approxNearestSearch(p, oa, oad);
      fresh.approxNearestSearch(p, fa, fad);
      ref.approxNearestSearch(p, ra, rad);
      ASSERT_EQ(oa, fa) << "step " << step;
      ASSERT_EQ(oad, rad) << "step " << step;
    }
  }
}

// The occupancy octree's leaves are the tree's cells: its branch index follows them in place too.
TEST(OctreeSearchAgreement, OccupancyBranchesFollowSetAndDeletedVoxels) {
  pcl::fot::OctreePointCloudOccupancy<PointXYZ> ours(0.25);
  pcl::octree::OctreePointCloudOccupancy<PointXYZ> ref(0.25);
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> coordinate(-2.0f, 2.0f);
  std::vector<PointXYZ> set;
  for (int step = 0; step < 300; ++step) {
    if (step % 7 == 6) {
      const PointXYZ victim = set[rng() % set.size()];
      ours.deleteVoxelAtPoint(victim);
      ref.deleteVoxelAtPoint(victim);
    } else {
      set.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
      ours.setOccupiedVoxelAtPoint(set.back());
      ref.setOccupiedVoxelAtPoint(set.back());
    }
    const auto copy = ours;  // builds its branch index afresh
    ASSERT_EQ(ours.getBranchCount(), ref.getBranchCount()) << "step " << step;
    ASSERT_EQ(nodesOf(ours), nodesOf(copy)) << "step " << step;
  }
}
