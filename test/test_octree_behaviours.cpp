// PCL 1.13's own octree tests (test/octree/test_octree.cpp, test_octree_iterator.cpp), the behaviours the
// agreement tests do not check, in our own words: each test builds the look-alike and pcl::octree on one
// small seeded cloud, compares them, and checks properties that follow from how the cloud was made.
//
//   PCL case                                       here
//   OctreePointCloudSierpinskiTest (6 cases),      SierpinskiOctree.*: counts, orders, keys, bounds, steps
//     Octree_Pointcloud_Iterator_Test
//   OctreePointCloudAdjacencyBeginEndIterators-    AdjacencyOctree.IteratorsCompareAsPcls
//     Test (10 cases)
//   Octree_Pointcloud_Adjacency                    AdjacencyOctree.LeafVector..., NeighbourCounts...
//   Octree_Dynamic_Depth_Test                      DynamicDepth.*
//   Octree_Pointcloud_Test                         OctreeContents.SinglePoint..., VoxelSearch...
//   Octree_Pointcloud_Occupancy_Test               OctreeContents.DeepOccupancyAndDeletion
//   Octree_Pointcloud_Density_Test                 OctreeContents.DensityOfARegularGrid
//   Octree_Pointcloud_Change_Detector_Test         OctreeContents.ChangeDetector...
//   Octree_Pointcloud_Voxel_Centroid_Test          OctreeContents.CentroidsAcrossTwoClouds
//   Octree_Pointcloud_Nearest_K_Neighbour_Search,  OctreeSearch.AnswersMatchBruteForce
//     _Box_Search, _Approx_Nearest_Neighbour_Search, _Neighbours_Within_Radius_Search
//   Octree_Pointcloud_Ray_Traversal                OctreeSearch.RayThroughPointsFindsTheirVoxels
//   Octree_Pointcloud_Bounds                       BoundingBox.*
//   (none: leaves built as runs of one array)      OctreeContents.LeafContainersTake..., RunsOfGone...
//
// The rest is covered elsewhere: every iterator node by node, boxes, deletions and rays on scans
// (test_octree_point_cloud); each leaf-holding class call for call (test_octree_family_agreement); every
// search call for call (test_octree_search_agreement). PCL's OctreeBase/Octree2BufBase cases have no pcl::fot
// counterpart: the look-alikes are the point cloud octrees only.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <ostream>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <pcl/common/point_tests.h>  // PCL 1.13's octree headers use isFinite without including it
#include <pcl/octree/octree.h>

#include <pcl_fot/pcl/octree/octree.h>
#include <pcl_fot/pcl/octree/octree_leaf_nodes.h>

using pcl::Indices;
using pcl::PointXYZ;
using pcl::uindex_t;
using Cloud = pcl::PointCloud<PointXYZ>;

namespace {

/** The node an iterator stands on. */
struct Stop {
  uindex_t depth, x, y, z;
  bool leaf;
  bool operator==(const Stop& o) const {
    return depth == o.depth && x == o.x && y == o.y && z == o.z && leaf == o.leaf;
  }
};

std::ostream& operator<<(std::ostream& os, const Stop& s) {
  return os << (s.leaf ? "leaf" : "branch") << " (" << s.x << ", " << s.y << ", " << s.z << ") at depth "
            << s.depth;
}

/** Every node from `it` to `end`; works for pcl::octree's iterators and ours alike. */
template <typename It>
std::vector<Stop> walk(It it, const It& end) {
  std::vector<Stop> stops;
  for (; it != end; ++it) {
    const auto& k = it.getCurrentOctreeKey();
    stops.push_back({it.getCurrentOctreeDepth(), k.x, k.y, k.z, it.isLeafNode()});
  }
  return stops;
}

/** The node's path from the root as octal digits (PCL's child index: x bit 4, y bit 2, z bit 1), padded to
 * the tree's depth: depth first visits nodes by (code, depth), breadth first by (depth, code). */
std::uint64_t pathCode(const Stop& s, uindex_t tree_depth) {
  std::uint64_t code = 0;
  for (uindex_t level = 0; level < s.depth; ++level) {
    const uindex_t bit = s.depth - 1 - level;
    code = code * 8 + (((s.x >> bit) & 1) << 2 | ((s.y >> bit) & 1) << 1 | ((s.z >> bit) & 1));
  }
  return code << (3 * (tree_depth - s.depth));
}

/** The voxel key of a point, as PCL computes it from the box. */
std::array<long, 3> keyOf(const PointXYZ& p, const double lo[3], double res) {
  return {long((p.x - lo[0]) / res), long((p.y - lo[1]) / res), long((p.z - lo[2]) / res)};
}

template <typename Octree>
void box(const Octree& t, double lo[3], double hi[3]) {
  t.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
}

template <typename A, typename B>
void expectSameBox(const A& a, const B& b) {
  double alo[3], ahi[3], blo[3], bhi[3];
  box(a, alo, ahi);
  box(b, blo, bhi);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(alo[i], blo[i]) << "axis " << i;
    EXPECT_EQ(ahi[i], bhi[i]) << "axis " << i;
  }
  EXPECT_EQ(a.getTreeDepth(), b.getTreeDepth());
}

std::size_t powerOf4(uindex_t n) {
  return std::size_t(1) << (2 * n);
}

}  // namespace

// ---- Iterators on a Sierpinski tetrahedron: exactly four children of each branch are occupied, so every
// count is known in advance.

class SierpinskiOctree : public ::testing::Test {
 protected:
  static constexpr uindex_t kDepth = 6;
  static constexpr double kRes = 1.0 / (1 << kDepth);

  SierpinskiOctree() : ref_(kRes), ours_(kRes), twin_(kRes), cloud_(new Cloud) {}

  void SetUp() override {
    // Each voxel of the unit cube whose every step down from the root goes to a child with an even number of
    // 1 bits in its index (0, 3, 5 or 6); two points in each: its centre and a seeded one inside it.
    const int even_children[4] = {0, 3, 5, 6};
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> inside(0.1, 0.9);
    for (std::uint32_t path = 0; path < powerOf4(kDepth); ++path) {
      uindex_t k[3] = {0, 0, 0};
      for (uindex_t level = 0; level < kDepth; ++level) {
        const int child = even_children[(path >> (2 * level)) & 3];
        for (int a = 0; a < 3; ++a) k[a] = (k[a] << 1) | ((child >> (2 - a)) & 1);
      }
      cloud_->emplace_back(float((k[0] + 0.5) * kRes), float((k[1] + 0.5) * kRes),
                           float((k[2] + 0.5) * kRes));
      cloud_->emplace_back(float((k[0] + inside(rng)) * kRes), float((k[1] + inside(rng)) * kRes),
                           float((k[2] + inside(rng)) * kRes));
    }
    ref_.defineBoundingBox(0, 0, 0, 1, 1, 1);
    ref_.setInputCloud(cloud_);
    ref_.addPointsFromInputCloud();
    for (auto* t : {&ours_, &twin_}) {
      t->defineBoundingBox(0, 0, 0, 1, 1, 1);
      t->setInputCloud(cloud_);
      t->addPointsFromInputCloud();
    }
  }

  static bool evenParity(const Stop& s) {
    for (uindex_t bit = 0; bit < s.depth; ++bit)
      if ((((s.x >> bit) & 1) + ((s.y >> bit) & 1) + ((s.z >> bit) & 1)) % 2) return false;
    return true;
  }

  pcl::octree::OctreePointCloud<PointXYZ> ref_;
  pcl::fot::OctreePointCloud<PointXYZ> ours_, twin_;  // twin_: the same points, another octree
  Cloud::Ptr cloud_;
};

TEST_F(SierpinskiOctree, CountsOfEveryWalk) {
  ASSERT_EQ(ours_.getTreeDepth(), kDepth);
  const std::size_t leaves = powerOf4(kDepth);
  std::size_t branches = 0;
  for (uindex_t d = 0; d < kDepth; ++d) branches += powerOf4(d);
  EXPECT_EQ(ours_.getLeafCount(), leaves);
  EXPECT_EQ(ours_.getBranchCount(), branches);
  EXPECT_EQ(ref_.getBranchCount(), branches);

  // Node types as getCurrentOctreeNode reports them, for the walks over all nodes and over leaves.
  auto countTypes = [](auto it, const auto& end) {
    std::pair<std::size_t, std::size_t> n{0, 0};  // branches, leaves
    for (; it != end; ++it) {
      const auto type = it.getCurrentOctreeNode()->getNodeType();
      EXPECT_EQ(type == pcl::octree::LEAF_NODE, it.isLeafNode());
      (type == pcl::octree::BRANCH_NODE ? n.first : n.second)++;
    }
    return n;
  };
  using Counts = std::pair<std::size_t, std::size_t>;
  EXPECT_EQ(countTypes(ours_.begin(), ours_.end()), Counts(branches, leaves));
  EXPECT_EQ(countTypes(ours_.breadth_begin(), ours_.breadth_end()), Counts(branches, leaves));
  EXPECT_EQ(countTypes(ours_.leaf_depth_begin(), ours_.leaf_depth_end()), Counts(0, leaves));
  EXPECT_EQ(countTypes(ours_.leaf_breadth_begin(), ours_.leaf_breadth_end()), Counts(0, leaves));

  // Cut at each depth: all nodes down to it; at it alone; leaves only at the full depth.
  std::size_t down_to = 1;
  for (uindex_t d = 1; d <= kDepth; ++d) {
    SCOPED_TRACE(::testing::Message() << "depth " << d);
    down_to += powerOf4(d);
    const auto depth_first = walk(ours_.begin(d), ours_.end());
    EXPECT_EQ(depth_first.size(), down_to);
    EXPECT_EQ(walk(ours_.breadth_begin(d), ours_.breadth_end()).size(), down_to);
    const auto fixed = walk(ours_.fixed_depth_begin(d), ours_.fixed_depth_end());
    EXPECT_EQ(fixed.size(), powerOf4(d));
    for (const Stop& s : fixed) ASSERT_EQ(s.depth, d);
    EXPECT_EQ(walk(ours_.leaf_depth_begin(d), ours_.leaf_depth_end()).size(), d == kDepth ? leaves : 0);
    EXPECT_EQ(walk(ours_.leaf_breadth_begin(d), ours_.leaf_breadth_end()).size(), d == kDepth ? leaves : 0);
    // The same nodes as pcl::octree, in its order.
    EXPECT_EQ(depth_first, walk(ref_.begin(d), ref_.end()));
    EXPECT_EQ(walk(ours_.breadth_begin(d), ours_.breadth_end()),
              walk(ref_.breadth_begin(d), ref_.breadth_end()));
    EXPECT_EQ(fixed, walk(ref_.fixed_depth_begin(d), ref_.fixed_depth_end()));
    EXPECT_EQ(walk(ours_.leaf_depth_begin(d), ours_.leaf_depth_end()),
              walk(ref_.leaf_depth_begin(d), ref_.leaf_depth_end()));
  }
  EXPECT_EQ(walk(ours_.fixed_depth_begin(), ours_.fixed_depth_end()).size(), 1u) << "depth 0: the root";
  EXPECT_EQ(walk(ours_.fixed_depth_begin(kDepth + 1), ours_.fixed_depth_end()),
            walk(ref_.fixed_depth_begin(kDepth + 1), ref_.fixed_depth_end()))
      << "deeper than the tree";
}

TEST_F(SierpinskiOctree, OrdersAndKeys) {
  const auto depth_first = walk(ours_.begin(), ours_.end());
  const auto breadth_first = walk(ours_.breadth_begin(), ours_.breadth_end());
  ASSERT_EQ(depth_first, walk(ref_.begin(), ref_.end()));
  ASSERT_EQ(breadth_first, walk(ref_.breadth_begin(), ref_.breadth_end()));
  auto preorder = [](const Stop& a, const Stop& b) {
    return std::make_pair(pathCode(a, kDepth), a.depth) < std::make_pair(pathCode(b, kDepth), b.depth);
  };
  auto levelOrder = [](const Stop& a, const Stop& b) {
    return std::make_pair(a.depth, pathCode(a, kDepth)) < std::make_pair(b.depth, pathCode(b, kDepth));
  };
  // Strictly increasing: each node once, parents before children, children in index order.
  for (const auto& [name, nodes, less] :
       {std::make_tuple("depth first", depth_first, +preorder),
        std::make_tuple("breadth first", breadth_first, +levelOrder),
        std::make_tuple("leaves depth first", walk(ours_.leaf_depth_begin(), ours_.leaf_depth_end()),
                        +preorder),
        std::make_tuple("leaves breadth first", walk(ours_.leaf_breadth_begin(), ours_.leaf_breadth_end()),
                        +levelOrder),
        std::make_tuple("fixed depth 4", walk(ours_.fixed_depth_begin(4), ours_.fixed_depth_end()),
                        +levelOrder)}) {
    SCOPED_TRACE(name);
    for (std::size_t i = 1; i < nodes.size(); ++i) ASSERT_TRUE(less(nodes[i - 1], nodes[i])) << nodes[i];
    for (const Stop& s : nodes) ASSERT_TRUE(evenParity(s)) << s << " is off the fractal";
  }
  // Breadth first: depths never decrease, so every branch comes before every leaf.
  const auto first_leaf =
      std::find_if(breadth_first.begin(), breadth_first.end(), [](const Stop& s) { return s.leaf; });
  EXPECT_TRUE(std::none_of(first_leaf, breadth_first.end(), [](const Stop& s) { return !s.leaf; }));
}

TEST_F(SierpinskiOctree, LeavesHoldTheirPointsInsideTheirBounds) {
  double lo[3], hi[3];
  box(ours_, lo, hi);
  std::vector<int> seen(cloud_->size(), 0);
  for (auto it = ours_.begin(); it != ours_.end(); ++it) {
    Eigen::Vector3f vmin, vmax;
    ours_.getVoxelBounds(it, vmin, vmax);
    const float side = float(std::ldexp(1.0, -int(it.getCurrentOctreeDepth())));
    for (int a = 0; a < 3; ++a) {
      ASSERT_GE(vmin[a], lo[a] - 1e-6);
      ASSERT_LE(vmax[a], hi[a] + 1e-6);
      ASSERT_NEAR(vmax[a] - vmin[a], side, 1e-6);
    }
    if (!it.isLeafNode()) continue;
    for (const auto i : it.getLeafContainer().getPointIndicesVector()) {
      ++seen[i];
      const Eigen::Vector3f p = (*cloud_)[i].getVector3fMap();
      ASSERT_TRUE((p.array() >= vmin.array()).all() && (p.array() <= vmax.array()).all()) << "point " << i;
    }
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }))
      << "each point in one leaf";

  // The occupied voxels' centres, in the leaves' order: each the exact centre of that leaf's voxel.
  pcl::fot::OctreePointCloud<PointXYZ>::AlignedPointTVector centres;
  ASSERT_EQ(ours_.getOccupiedVoxelCenters(centres), powerOf4(kDepth));
  std::size_t i = 0;
  for (auto it = ours_.leaf_depth_begin(); it != ours_.leaf_depth_end(); ++it, ++i) {
    const auto& k = it.getCurrentOctreeKey();
    ASSERT_EQ(
        centres[i].getVector3fMap(),
        Eigen::Vector3f(float((k.x + 0.5) * kRes), float((k.y + 0.5) * kRes), float((k.z + 0.5) * kRes)));
    ASSERT_TRUE(ours_.isVoxelOccupiedAtPoint(centres[i]));
  }
}

TEST_F(SierpinskiOctree, IteratorsStepCopyAndCompare) {
  // Positions are told apart by the walk left from them: equality, as PCL's, looks at keys only, and the
  // root shares key 0 with the first nodes below it.
  const auto all = walk(ours_.begin(), ours_.end());
  auto rest = [&](std::size_t from) { return std::vector<Stop>(all.begin() + from, all.end()); };
  auto it = ours_.begin();
  const auto was = it++;  // post-increment hands back where it stood
  EXPECT_EQ(walk(was, ours_.end()), all);
  EXPECT_EQ(walk(it, ours_.end()), rest(1));
  auto& same = ++it;  // pre-increment hands back the iterator itself
  EXPECT_EQ(&same, &it);
  EXPECT_EQ(walk(it, ours_.end()), rest(2));
  // A copy (constructed or assigned) walks on by itself.
  auto copy = it;
  pcl::fot::OctreePointCloud<PointXYZ>::Iterator assigned;
  assigned = it;
  ++copy;
  EXPECT_EQ(walk(copy, ours_.end()), rest(3));
  EXPECT_EQ(walk(assigned, ours_.end()), rest(2));
  EXPECT_EQ(walk(it, ours_.end()), rest(2));
  // A for loop stepping with post-increment visits every leaf; its end equals any end of the same octree.
  std::size_t n = 0;
  auto leaf = ours_.leaf_depth_begin();
  for (; leaf != ours_.leaf_depth_end(); leaf++) ++n;
  EXPECT_EQ(n, ours_.getLeafCount());
  EXPECT_TRUE(leaf == ours_.end());
  EXPECT_TRUE(leaf == ours_.breadth_end());
  EXPECT_TRUE(leaf != twin_.leaf_depth_end()) << "ends of two octrees differ";
  EXPECT_TRUE(ours_.begin() != twin_.begin()) << "same nodes, other octree";
}

// ---- OctreePointCloudAdjacency

namespace {

/** How iterators of two octrees with the same points compare, by name. */
template <typename Octree>
std::map<std::string, bool> iteratorComparisons(Octree& a, Octree& b) {
  const uindex_t depth = a.getTreeDepth();
  std::map<std::string, bool> r;
  auto kind = [&](const std::string& name, auto begin, auto end) {
    r[name + " begin == begin"] = begin(a, 0) == begin(a, 0);
    r[name + " begin == other's begin"] = begin(a, 0) == begin(b, 0);
    r[name + " begin(1) == begin(depth)"] = begin(a, 1) == begin(a, depth);
    r[name + " begin() == begin(depth)"] = begin(a, 0) == begin(a, depth);
    r[name + " begin(1) == other's begin(1)"] = begin(a, 1) == begin(b, 1);
    r[name + " end == end"] = end(a) == end(a);
    r[name + " end == other's end"] = end(a) == end(b);
    r[name + " begin == end"] = begin(a, 0) == end(a);
  };
  kind(
      "depth", [](auto& t, uindex_t d) { return t.depth_begin(d); }, [](auto& t) { return t.depth_end(); });
  kind(
      "breadth", [](auto& t, uindex_t d) { return t.breadth_begin(d); },
      [](auto& t) { return t.breadth_end(); });
  kind(
      "leaf depth", [](auto& t, uindex_t d) { return t.leaf_depth_begin(d); },
      [](auto& t) { return t.leaf_depth_end(); });
  kind(
      "leaf breadth", [](auto& t, uindex_t d) { return t.leaf_breadth_begin(d); },
      [](auto& t) { return t.leaf_breadth_end(); });
  kind(
      "fixed", [](auto& t, uindex_t d) { return t.fixed_depth_begin(d); },
      [](auto& t) { return t.fixed_depth_end(); });
  r["fixed begin() == begin(0)"] = a.fixed_depth_begin() == a.fixed_depth_begin(0);
  return r;
}

}  // namespace

TEST(AdjacencyOctree, IteratorsCompareAsPcls) {
  const auto cloud = [] {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-4.0f, 4.0f);
    Cloud::Ptr c(new Cloud);
    for (int i = 0; i < 120; ++i) c->emplace_back(u(rng), u(rng), u(rng));
    return c;
  }();
  pcl::octree::OctreePointCloudAdjacency<PointXYZ> ref_a(0.7), ref_b(0.7);
  pcl::fot::OctreePointCloudAdjacency<PointXYZ> a(0.7), b(0.7);
  for (auto* t : {&ref_a, &ref_b}) t->setInputCloud(cloud), t->addPointsFromInputCloud();
  for (auto* t : {&a, &b}) t->setInputCloud(cloud), t->addPointsFromInputCloud();
  const auto ours = iteratorComparisons(a, b);
  EXPECT_EQ(ours, iteratorComparisons(ref_a, ref_b));
  // What those mean: one octree's iterators agree with themselves, never with another octree's; the maximum
  // depth counts, its default is the tree's depth (the root for the fixed-depth walk).
  for (const std::string kind : {"depth", "breadth", "leaf depth", "leaf breadth", "fixed"}) {
    EXPECT_TRUE(ours.at(kind + " begin == begin")) << kind;
    EXPECT_FALSE(ours.at(kind + " begin == other's begin")) << kind;
    EXPECT_FALSE(ours.at(kind + " begin(1) == begin(depth)")) << kind;
    EXPECT_FALSE(ours.at(kind + " begin(1) == other's begin(1)")) << kind;
    EXPECT_TRUE(ours.at(kind + " end == end")) << kind;
    EXPECT_FALSE(ours.at(kind + " end == other's end")) << kind;
    EXPECT_FALSE(ours.at(kind + " begin == end")) << kind;
  }
  for (const std::string kind : {"depth", "breadth", "leaf depth", "leaf breadth"})
    EXPECT_TRUE(ours.at(kind + " begin() == begin(depth)")) << kind;
  EXPECT_TRUE(ours.at("fixed begin() == begin(0)"));
  EXPECT_FALSE(ours.at("fixed begin() == begin(depth)"));
}

TEST(AdjacencyOctree, LeafVectorMatchesLeavesAndNeighbours) {
  const auto cloud = [] {
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> u(0.0f, 6.0f);
    Cloud::Ptr c(new Cloud);
    for (int i = 0; i < 150; ++i) c->emplace_back(u(rng), u(rng), u(rng));
    return c;
  }();
  const double res = 1.0;
  pcl::octree::OctreePointCloudAdjacency<PointXYZ> ref(res);
  pcl::fot::OctreePointCloudAdjacency<PointXYZ> ours(res);
  ref.setInputCloud(cloud), ref.addPointsFromInputCloud();
  ours.setInputCloud(cloud), ours.addPointsFromInputCloud();
  ASSERT_EQ(ours.size(), ours.getLeafCount());
  ASSERT_EQ(ours.size(), ref.size());
  ASSERT_EQ(std::size_t(ours.end() - ours.begin()), ours.size());
  EXPECT_THROW(ours.at(ours.size()), std::out_of_range);

  // Brute force: the points of each voxel, and the occupied voxels among the 27 around each.
  double lo[3], hi[3];
  box(ours, lo, hi);
  std::map<std::array<long, 3>, uindex_t> points_in;
  for (const auto& p : *cloud) ++points_in[keyOf(p, lo, res)];
  std::size_t i = 0;
  for (auto it = ours.leaf_depth_begin(); it != ours.leaf_depth_end(); ++it, ++i) {
    ASSERT_EQ(ours.at(i), &it.getLeafContainer()) << "the leaf vector follows the depth-first leaves";
    ASSERT_EQ(*(ours.begin() + i), ours.at(i));
    const auto& k = it.getCurrentOctreeKey();
    const std::array<long, 3> key{long(k.x), long(k.y), long(k.z)};
    std::size_t around = 0;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) around += points_in.count({key[0] + dx, key[1] + dy, key[2] + dz});
    ASSERT_EQ(ours.at(i)->size(), around) << "leaf " << i;
    ASSERT_EQ(ours.at(i)->getPointCounter(), points_in.at(key));
    ASSERT_EQ(ours.at(i)->size(), ref.at(i)->size());
    ASSERT_EQ(ours.at(i)->getPointCounter(), ref.at(i)->getPointCounter());
  }
}

TEST(AdjacencyOctree, NeighbourCountsAroundABlock) {
  const double res = 0.05;
  // The box follows the cloud's extremes: two corners fix it, so the voxels' centres are known beforehand.
  Cloud::Ptr corners(new Cloud);
  corners->emplace_back(-1.0f, -1.0f, -1.0f);
  corners->emplace_back(1.5f, 1.5f, 1.5f);
  pcl::fot::OctreePointCloudAdjacency<PointXYZ> probe(res);
  probe.setInputCloud(corners), probe.addPointsFromInputCloud();
  double lo[3], hi[3];
  box(probe, lo, hi);
  auto centre = [&](long x, long y, long z) {
    return PointXYZ(float(lo[0] + (x + 0.5) * res), float(lo[1] + (y + 0.5) * res),
                    float(lo[2] + (z + 0.5) * res));
  };
  Cloud::Ptr cloud(new Cloud(*corners));
  for (int dx = -1; dx <= 1; ++dx)  // a full 3x3x3 block around voxel (12, 14, 16)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) cloud->push_back(centre(12 + dx, 14 + dy, 16 + dz));
  cloud->push_back(centre(30, 30, 30));  // alone
  cloud->push_back(centre(31, 32, 30));  // two apart in y: not a neighbour of the lone one
  pcl::octree::OctreePointCloudAdjacency<PointXYZ> ref(res);
  pcl::fot::OctreePointCloudAdjacency<PointXYZ> ours(res);
  ref.setInputCloud(cloud), ref.addPointsFromInputCloud();
  ours.setInputCloud(cloud), ours.addPointsFromInputCloud();
  double lo2[3], hi2[3];
  box(ours, lo2, hi2);
  ASSERT_TRUE(std::equal(lo, lo + 3, lo2)) << "the extra points did not move the box";
  // A voxel's neighbours, itself included: 27 in the block's middle, 18 on a face, 12 on an edge, 8 at a
  // corner.
  for (const auto& [at, expected] :
       {std::make_pair(centre(12, 14, 16), 27u), std::make_pair(centre(11, 14, 16), 18u),
        std::make_pair(centre(11, 13, 16), 12u), std::make_pair(centre(11, 13, 15), 8u),
        std::make_pair(centre(30, 30, 30), 1u)}) {
    ASSERT_NE(ours.getLeafContainerAtPoint(at), nullptr);
    EXPECT_EQ(ours.getLeafContainerAtPoint(at)->size(), expected);
    EXPECT_EQ(ref.getLeafContainerAtPoint(at)->size(), expected);
  }
  EXPECT_EQ(ours.getLeafContainerAtPoint(centre(20, 20, 20)), nullptr) << "an empty voxel has no container";
}

// ---- Dynamic depth

TEST(DynamicDepth, LoneLeafStaysShallowCrowdSinksToTheBottom) {
  Cloud::Ptr cloud(new Cloud);
  cloud->emplace_back(-0.4f, 0.2f, 1.0f);  // the box's low corner
  for (int i = 0; i < 12; ++i)
    cloud->emplace_back(0.3f, 0.9f, 1.7f);  // one spot, twelve times: its high corner
  pcl::octree::OctreePointCloudPointVector<PointXYZ> ref(0.02);
  pcl::fot::OctreePointCloudPointVector<PointXYZ> ours(0.02);
  ours.setInputCloud(cloud), ours.defineBoundingBox(), ours.enableDynamicDepth(4);
  ref.setInputCloud(cloud), ref.defineBoundingBox(), ref.enableDynamicDepth(4);
  ref.addPointsFromInputCloud();
  ours.addPointsFromInputCloud();
  // The box (2^6 voxels of 2 cm, centred on the 0.7 m the points span) splits between the two corners on
  // every axis, so the lone point needs only a child of the root; the crowd splits down to the last level.
  ASSERT_EQ(ours.getTreeDepth(), 6u);
  const auto leaves = walk(ours.leaf_depth_begin(), ours.leaf_depth_end());
  ASSERT_EQ(leaves, walk(ref.leaf_depth_begin(), ref.leaf_depth_end()));
  ASSERT_EQ(leaves.size(), 2u);
  auto it = ours.leaf_depth_begin();
  EXPECT_EQ(it.getCurrentOctreeDepth(), 1u);
  EXPECT_EQ(it.getLeafContainer().getPointIndicesVector(), Indices{0});
  ++it;
  EXPECT_EQ(it.getCurrentOctreeDepth(), ours.getTreeDepth());
  EXPECT_EQ(it.getLeafContainer().getSize(), 12u);
}

TEST(DynamicDepth, LeavesHoldFewPointsInsideTheirBoundsAndTheTreeIsReusable) {
  std::mt19937 rng(21);
  pcl::fot::OctreePointCloudPointVector<PointXYZ> reused(0.05);
  for (const std::size_t max_per_leaf : {2, 5}) {
    SCOPED_TRACE(::testing::Message() << "at most " << max_per_leaf << " per shallow leaf");
    std::uniform_real_distribution<float> u(0.0f, 10.0f);
    Cloud::Ptr cloud(new Cloud);
    for (int i = 0; i < 300; ++i) cloud->emplace_back(u(rng), u(rng), u(rng));
    pcl::octree::OctreePointCloudPointVector<PointXYZ> ref(0.05);
    pcl::fot::OctreePointCloudPointVector<PointXYZ> ours(0.05);
    ref.setInputCloud(cloud), ref.defineBoundingBox(), ref.enableDynamicDepth(max_per_leaf);
    ours.setInputCloud(cloud), ours.defineBoundingBox(), ours.enableDynamicDepth(max_per_leaf);
    ref.addPointsFromInputCloud();
    ours.addPointsFromInputCloud();
    ASSERT_EQ(walk(ours.leaf_depth_begin(), ours.leaf_depth_end()),
              walk(ref.leaf_depth_begin(), ref.leaf_depth_end()));

    std::vector<int> seen(cloud->size(), 0);
    std::size_t leaves = 0;
    for (auto it = ours.leaf_depth_begin(); it != ours.leaf_depth_end(); ++it, ++leaves) {
      ASSERT_EQ(it.getCurrentOctreeNode()->getNodeType(), pcl::octree::LEAF_NODE);
      const auto& indices = it.getLeafContainer().getPointIndicesVector();
      if (it.getCurrentOctreeDepth() < ours.getTreeDepth()) {
        ASSERT_LE(indices.size(), max_per_leaf);
      }
      Eigen::Vector3f vmin, vmax;
      ours.getVoxelBounds(it, vmin, vmax);
      for (const auto i : indices) {
        ++seen[i];
        const Eigen::Vector3f p = (*cloud)[i].getVector3fMap();
        ASSERT_TRUE((p.array() >= vmin.array()).all() && (p.array() <= vmax.array()).all()) << "point " << i;
      }
    }
    EXPECT_EQ(leaves, ours.getLeafCount());
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
    // Breadth first, leaves of several depths: depths never decrease.
    uindex_t last = 0;
    for (auto it = ours.breadth_begin(); it != ours.breadth_end(); ++it) {
      ASSERT_GE(it.getCurrentOctreeDepth(), last);
      last = it.getCurrentOctreeDepth();
    }
    // One octree emptied with deleteTree and refilled (box and dynamic depth set again) ends as a fresh one.
    reused.deleteTree();
    EXPECT_EQ(reused.getLeafCount(), 0u);
    reused.setInputCloud(cloud), reused.defineBoundingBox(), reused.enableDynamicDepth(max_per_leaf);
    reused.addPointsFromInputCloud();
    expectSameBox(reused, ours);
    EXPECT_EQ(walk(reused.leaf_depth_begin(), reused.leaf_depth_end()),
              walk(ours.leaf_depth_begin(), ours.leaf_depth_end()));
  }
}

// ---- What the leaf-holding octrees hold

TEST(OctreeContents, SinglePointOctreeKeepsOnePointPerVoxel) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  Cloud::Ptr ours_cloud(new Cloud), ref_cloud(new Cloud);
  pcl::octree::OctreePointCloudSinglePoint<PointXYZ> ref(0.5);
  pcl::fot::OctreePointCloudSinglePoint<PointXYZ> ours(0.5);
  ref.setInputCloud(ref_cloud);
  ours.setInputCloud(ours_cloud);
  for (int i = 0; i < 400; ++i) {
    const PointXYZ p(u(rng), u(rng), u(rng));
    if (!ours.isVoxelOccupiedAtPoint(p)) ours.addPointToCloud(p, ours_cloud);  // only the first of each voxel
    if (!ref.isVoxelOccupiedAtPoint(p)) ref.addPointToCloud(p, ref_cloud);
  }
  ASSERT_EQ(ours_cloud->size(), ref_cloud->size());
  ASSERT_LT(ours_cloud->size(), 400u) << "some voxels were met twice";
  EXPECT_EQ(ours.getLeafCount(), ours_cloud->size());
  for (auto it = ours.leaf_depth_begin(); it != ours.leaf_depth_end(); ++it) {
    const auto i = it.getLeafContainer().getPointIndex();
    ASSERT_TRUE(ours.isVoxelOccupiedAtPoint((*ours_cloud)[i]));
    Eigen::Vector3f vmin, vmax;
    ours.getVoxelBounds(it, vmin, vmax);
    const Eigen::Vector3f p = (*ours_cloud)[i].getVector3fMap();
    ASSERT_TRUE((p.array() >= vmin.array()).all() && (p.array() <= vmax.array()).all());
  }
  for (std::size_t i = 0; i < ours_cloud->size(); ++i) {
    ASSERT_EQ((*ours_cloud)[i].getVector3fMap(), (*ref_cloud)[i].getVector3fMap());
    ASSERT_TRUE(ours.isVoxelOccupiedAtPoint((*ours_cloud)[i]));
    ours.deleteVoxelAtPoint((*ours_cloud)[i]);
    ASSERT_FALSE(ours.isVoxelOccupiedAtPoint((*ours_cloud)[i]));
    ASSERT_EQ(ours.getLeafCount(), ours_cloud->size() - i - 1);
  }
}

TEST(OctreeContents, DeepOccupancyAndDeletion) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> half(0.0f, 5.0f), whole(0.0f, 10.0f);
  Cloud::Ptr cloud(new Cloud);
  for (int i = 0; i < 300; ++i) cloud->emplace_back(half(rng), whole(rng), whole(rng));
  // PCL centres its first box on the first point, which thus lies on a voxel face; once the box has grown,
  // rounding (p - min) / res can put it in the voxel beside, so at 10 µm that point's voxel reads empty. Only
  // agreement is checked there.
  {
    pcl::octree::OctreePointCloudOccupancy<PointXYZ> ref(1e-5);
    pcl::fot::OctreePointCloudOccupancy<PointXYZ> ours(1e-5);
    ref.setInputCloud(cloud), ref.addPointsFromInputCloud();
    ours.setInputCloud(cloud), ours.addPointsFromInputCloud();
    for (const PointXYZ& p : *cloud) ASSERT_EQ(ours.isVoxelOccupiedAtPoint(p), ref.isVoxelOccupiedAtPoint(p));
  }
  // Voxels of 2^-17 m (7.6 µm), so that every key is computed exactly: a tree over 20 levels deep, each
  // point alone in its voxel.
  const double res = std::ldexp(1.0, -17);
  pcl::octree::OctreePointCloudOccupancy<PointXYZ> ref(res);
  pcl::fot::OctreePointCloudOccupancy<PointXYZ> ours(res);
  ref.setInputCloud(cloud), ref.addPointsFromInputCloud();
  ours.setInputCloud(cloud), ours.addPointsFromInputCloud();
  expectSameBox(ref, ours);
  EXPECT_GE(ours.getTreeDepth(), 20u);
  ASSERT_EQ(ours.getLeafCount(), cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const PointXYZ& p = (*cloud)[i];
    ASSERT_TRUE(ours.isVoxelOccupiedAtPoint(p)) << i;
    ours.deleteVoxelAtPoint(p);
    ref.deleteVoxelAtPoint(p);
    ASSERT_FALSE(ours.isVoxelOccupiedAtPoint(p)) << i;
    if (i + 1 < cloud->size()) {
      ASSERT_TRUE(ours.isVoxelOccupiedAtPoint((*cloud)[i + 1])) << "the next one stays";
    }
    if (i % 50 == 0) {
      ASSERT_EQ(ours.getLeafCount(), ref.getLeafCount());
      ASSERT_EQ(ours.getBranchCount(), ref.getBranchCount()) << "deletion prunes the same branches";
    }
  }
  EXPECT_EQ(ours.getLeafCount(), 0u);
  EXPECT_EQ(ours.getBranchCount(), ref.getBranchCount());
}

TEST(OctreeContents, VoxelSearchListsEveryPointOfTheVoxel) {
  const auto cloud = [] {
    std::mt19937 rng(6);
    std::uniform_real_distribution<float> u(0.0f, 4.0f);
    Cloud::Ptr c(new Cloud);
    for (int i = 0; i < 300; ++i) c->emplace_back(u(rng), u(rng), u(rng));
    return c;
  }();
  const double res = 0.5;
  pcl::octree::OctreePointCloudSearch<PointXYZ> ref(res);
  pcl::fot::OctreePointCloudSearch<PointXYZ> ours(res);
  ref.setInputCloud(cloud), ref.defineBoundingBox(), ref.addPointsFromInputCloud();
  ours.setInputCloud(cloud), ours.defineBoundingBox(), ours.addPointsFromInputCloud();
  expectSameBox(ref, ours);
  double lo[3], hi[3];
  box(ours, lo, hi);
  std::map<std::array<long, 3>, Indices> by_voxel;  // in index order, as points were added
  for (std::size_t i = 0; i < cloud->size(); ++i)
    by_voxel[keyOf((*cloud)[i], lo, res)].push_back(pcl::index_t(i));
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    Indices found, pcl_found;
    ASSERT_TRUE(ours.voxelSearch((*cloud)[i], found));
    ref.voxelSearch((*cloud)[i], pcl_found);
    ASSERT_EQ(found, by_voxel.at(keyOf((*cloud)[i], lo, res))) << "point " << i;
    ASSERT_EQ(found, pcl_found);
  }
  // Every node lies inside the box and no deeper than the tree; node types add up to the counts.
  std::size_t branches = 0, leaves = 0;
  for (auto it = ours.begin(); it != ours.end(); ++it) {
    ASSERT_LE(it.getCurrentOctreeDepth(), ours.getTreeDepth());
    Eigen::Vector3f vmin, vmax;
    ours.getVoxelBounds(it, vmin, vmax);
    for (int a = 0; a < 3; ++a) ASSERT_TRUE(vmin[a] >= lo[a] - 1e-4 && vmax[a] <= hi[a] + 1e-4);
    (it.getCurrentOctreeNode()->getNodeType() == pcl::octree::BRANCH_NODE ? branches : leaves)++;
  }
  EXPECT_EQ(leaves, by_voxel.size());
  EXPECT_EQ(leaves, ours.getLeafCount());
  EXPECT_EQ(branches, ours.getBranchCount());
}

TEST(OctreeContents, LeafContainersTakeTheirPointsAndKeepWhatIsAddedThroughThem) {
  // A cloud's leaves keep their indices in runs until a container is asked for; it is the leaf's from then
  // on, as in PCL: indices added through it, voxels deleted and the cloud added again answer as PCL's.
  const auto cloud = [] {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 4.0f);
    Cloud::Ptr c(new Cloud);
    for (int i = 0; i < 400; ++i) c->emplace_back(u(rng), u(rng), u(rng));
    return c;
  }();
  pcl::octree::OctreePointCloudSearch<PointXYZ> ref(0.5);
  pcl::fot::OctreePointCloudSearch<PointXYZ> ours(0.5);
  ref.setInputCloud(cloud), ref.addPointsFromInputCloud();
  ours.setInputCloud(cloud), ours.addPointsFromInputCloud();
  const auto expectSameAnswers = [&](const char* when) {
    SCOPED_TRACE(when);
    ASSERT_EQ(ours.getLeafCount(), ref.getLeafCount());
    for (std::size_t i = 0; i < cloud->size(); ++i) {
      Indices found, pcl_found, near, pcl_near;
      std::vector<float> d;
      ASSERT_EQ(ours.voxelSearch((*cloud)[i], found), ref.voxelSearch((*cloud)[i], pcl_found)) << i;
      ASSERT_EQ(found, pcl_found) << "point " << i;
      ours.radiusSearch((*cloud)[i], 0.7, near, d);
      ref.radiusSearch((*cloud)[i], 0.7, pcl_near, d);
      ASSERT_EQ(near, pcl_near) << "point " << i;
    }
  };
  expectSameAnswers("built");
  std::size_t taken = 0;
  auto it = ours.leaf_depth_begin();
  for (auto pcl_it = ref.leaf_depth_begin(); pcl_it != ref.leaf_depth_end(); ++pcl_it, ++it) {
    ASSERT_TRUE(it != ours.leaf_depth_end());
    ASSERT_EQ(it.getCurrentOctreeKey(), pcl_it.getCurrentOctreeKey());
    if (++taken % 2 == 0) continue;
    ASSERT_EQ(it.getLeafContainer().getPointIndicesVector(),
              pcl_it.getLeafContainer().getPointIndicesVector());
    const pcl::index_t again = it.getLeafContainer().getPointIndex();  // a point of the voxel, twice
    it.getLeafContainer().addPointIndex(again);
    pcl_it.getLeafContainer().addPointIndex(again);
  }
  expectSameAnswers("indices added through every other container");
  for (std::size_t i = 0; i < cloud->size(); i += 5) {
    ours.deleteVoxelAtPoint((*cloud)[i]);
    ref.deleteVoxelAtPoint((*cloud)[i]);
  }
  expectSameAnswers("voxels deleted");
  ours.addPointsFromInputCloud();
  ref.addPointsFromInputCloud();
  expectSameAnswers("the cloud added again");
}

TEST(OctreeContents, RunsOfGoneLeavesArePackedAway) {
  pcl::fot::OctreeLeafNodes<pcl::octree::OctreeContainerPointIndices> nodes;
  std::vector<std::uint32_t> positions(1000);
  Indices values(1000);
  for (std::uint32_t i = 0; i < 1000; ++i) positions[i] = 999 - i, values[i] = pcl::index_t(3 * i);
  for (int round = 0; round < 50; ++round) {
    nodes.reserveRuns(positions.size());
    nodes.addRun(0, positions.data(), positions.data() + 600, values.data());
    nodes.addRun(1, positions.data() + 600, positions.data() + 1000, values.data());
    Indices first, second;
    nodes.appendIndices(0, first);
    ASSERT_EQ(first.size(), 600u);
    ASSERT_EQ(first.front(), 3 * 999);
    ASSERT_EQ(nodes.size(1), 400u);
    nodes.appendIndices(1, second);
    ASSERT_EQ(nodes.node(1).getContainer().getPointIndicesVector(), second);  // leaf 1's container takes them
    nodes.drop(0);                                                            // leaf 0 is gone
    ASSERT_EQ(nodes.size(0), 0u);
  }
  // 50,000 indices went into runs; none is read any more, so little is kept.
  EXPECT_LE(nodes.runIndices(), 6000u);
}

TEST(OctreeContents, DensityOfARegularGrid) {
  // A 20^3 lattice, 10 cm apart, each point in the middle of its 10 cm cell of [0, 2)^3.
  Cloud::Ptr cloud(new Cloud);
  for (int z = 0; z < 20; ++z)
    for (int y = 0; y < 20; ++y)
      for (int x = 0; x < 20; ++x)
        cloud->emplace_back(0.1f * (x + 0.5f), 0.1f * (y + 0.5f), 0.1f * (z + 0.5f));
  pcl::octree::OctreePointCloudDensity<PointXYZ> ref_coarse(0.5), ref_fine(1e-5);
  pcl::fot::OctreePointCloudDensity<PointXYZ> coarse(0.5), fine(1e-5);
  for (auto* t : {&ref_coarse, &ref_fine}) t->defineBoundingBox(2.0, 2.0, 2.0), t->setInputCloud(cloud);
  for (auto* t : {&coarse, &fine}) t->defineBoundingBox(2.0, 2.0, 2.0), t->setInputCloud(cloud);
  for (auto* t : {&ref_coarse, &ref_fine}) t->addPointsFromInputCloud();
  for (auto* t : {&coarse, &fine}) t->addPointsFromInputCloud();
  // 50 cm voxels hold 5^3 lattice points each; 10 µm voxels one each, and none between the points.
  EXPECT_EQ(coarse.getLeafCount(), 64u);
  for (const PointXYZ& p : *cloud) {
    ASSERT_EQ(coarse.getVoxelDensityAtPoint(p), 125u);
    ASSERT_EQ(fine.getVoxelDensityAtPoint(p), 1u);
    ASSERT_EQ(ref_coarse.getVoxelDensityAtPoint(p), 125u);
    ASSERT_EQ(ref_fine.getVoxelDensityAtPoint(p), 1u);
    const PointXYZ between(p.x + 0.05f, p.y, p.z);
    ASSERT_EQ(fine.getVoxelDensityAtPoint(between), 0u);
  }
  EXPECT_EQ(fine.getLeafCount(), cloud->size());
}

TEST(OctreeContents, ChangeDetectorReportsOnlyPointsInNewVoxels) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.0f, 5.0f);
  Cloud::Ptr ours_cloud(new Cloud);
  for (int i = 0; i < 200; ++i) ours_cloud->emplace_back(u(rng), u(rng), u(rng));
  Cloud::Ptr ref_cloud(new Cloud(*ours_cloud));
  // 1/16 m voxels: exact keys for the first point, which PCL puts on a voxel face (see
  // DeepOccupancyAndDeletion).
  pcl::octree::OctreePointCloudChangeDetector<PointXYZ> ref(0.0625);
  pcl::fot::OctreePointCloudChangeDetector<PointXYZ> ours(0.0625);
  ref.setInputCloud(ref_cloud);
  ours.setInputCloud(ours_cloud);
  ref.addPointsFromInputCloud(), ours.addPointsFromInputCloud();
  ref.switchBuffers(), ours.switchBuffers();
  ref.addPointsFromInputCloud(), ours.addPointsFromInputCloud();
  Indices fresh;
  EXPECT_EQ(ours.getPointIndicesFromNewVoxels(fresh), 0u) << "the same cloud again";
  // Points far away (they grow the box) are new; they come after the first 200 in the cloud.
  for (int i = 0; i < 100; ++i) {
    const PointXYZ p(100.0f + u(rng), 100.0f + u(rng), 100.0f + u(rng));
    ours.addPointToCloud(p, ours_cloud);
    ref.addPointToCloud(p, ref_cloud);
  }
  Indices pcl_fresh;
  ASSERT_EQ(ours.getPointIndicesFromNewVoxels(fresh), 100u);
  ref.getPointIndicesFromNewVoxels(pcl_fresh);
  EXPECT_EQ(fresh, pcl_fresh);
  std::sort(fresh.begin(), fresh.end());
  for (int i = 0; i < 100; ++i) ASSERT_EQ(fresh[i], 200 + i);
}

TEST(OctreeContents, CentroidsAcrossTwoClouds) {
  // Three points in each of eight voxels of 1 m; then three more in each, through the same input cloud.
  auto fill = [](Cloud& c, const float offsets[3]) {
    c.clear();
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 3; ++j)
        c.emplace_back(i + offsets[j], (3 * i + 1) % 8 + offsets[2 - j], 7 - i + offsets[j]);
  };
  const float first[3] = {0.15f, 0.45f, 0.6f}, second[3] = {0.3f, 0.55f, 0.95f};
  Cloud::Ptr cloud(new Cloud);
  pcl::octree::OctreePointCloudVoxelCentroid<PointXYZ> ref(1.0);
  pcl::fot::OctreePointCloudVoxelCentroid<PointXYZ> ours(1.0);
  ref.defineBoundingBox(8.0);
  ours.defineBoundingBox(8.0);
  std::map<std::array<long, 3>, std::pair<Eigen::Vector3d, int>> sums;  // per voxel, in double
  const double lo[3] = {0, 0, 0};
  for (const float* offsets : {first, second}) {
    fill(*cloud, offsets);
    for (const auto& p : *cloud) {
      auto& s = sums.try_emplace(keyOf(p, lo, 1.0), Eigen::Vector3d::Zero(), 0).first->second;
      s.first += p.getVector3fMap().cast<double>();
      ++s.second;
    }
    ref.setInputCloud(cloud), ref.addPointsFromInputCloud();
    ours.setInputCloud(cloud), ours.addPointsFromInputCloud();
    pcl::fot::OctreePointCloudVoxelCentroid<PointXYZ>::AlignedPointTVector centroids, pcl_centroids;
    ASSERT_EQ(ours.getVoxelCentroids(centroids), 8u);
    ref.getVoxelCentroids(pcl_centroids);
    ASSERT_EQ(centroids.size(), pcl_centroids.size());
    for (std::size_t i = 0; i < centroids.size(); ++i) {
      const auto& s = sums.at(keyOf(centroids[i], lo, 1.0));  // the centroid lies in its own voxel
      const Eigen::Vector3d mean = s.first / s.second;
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(centroids[i].getVector3fMap()[a], mean[a], 1e-5);
      EXPECT_EQ(centroids[i].getVector3fMap(), pcl_centroids[i].getVector3fMap());
      PointXYZ at;
      ASSERT_TRUE(ours.getVoxelCentroidAtPoint(centroids[i], at));
      EXPECT_EQ(at.getVector3fMap(), centroids[i].getVector3fMap());
    }
  }
  EXPECT_EQ(sums.begin()->second.second, 6) << "both clouds went to the same voxels";
}

// ---- Searches against brute force

namespace {

float squaredDistance(const PointXYZ& a, const PointXYZ& b) {
  return (a.getVector3fMap() - b.getVector3fMap()).squaredNorm();
}

}  // namespace

TEST(OctreeSearch, AnswersMatchBruteForce) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Cloud::Ptr cloud(new Cloud);
  for (int i = 0; i < 400; ++i) cloud->emplace_back(10 * u(rng), 10 * u(rng), 5 * u(rng));
  for (const std::size_t max_per_leaf : {0, 5}) {
    SCOPED_TRACE(::testing::Message() << "dynamic depth " << max_per_leaf);
    pcl::octree::OctreePointCloudSearch<PointXYZ> ref(0.5);
    pcl::fot::OctreePointCloudSearch<PointXYZ> ours(0.5);
    ref.setInputCloud(cloud), ours.setInputCloud(cloud);
    if (max_per_leaf) ref.enableDynamicDepth(max_per_leaf), ours.enableDynamicDepth(max_per_leaf);
    ref.addPointsFromInputCloud(), ours.addPointsFromInputCloud();
    std::size_t approx_exact = 0;
    for (int q = 0; q < 40; ++q) {
      const PointXYZ query(10 * u(rng), 10 * u(rng), 10 * u(rng));
      std::vector<std::pair<float, pcl::index_t>> by_distance;
      for (std::size_t i = 0; i < cloud->size(); ++i)
        by_distance.emplace_back(squaredDistance((*cloud)[i], query), pcl::index_t(i));
      std::sort(by_distance.begin(), by_distance.end());

      const uindex_t k = 1 + q % 10;
      Indices idx;
      std::vector<float> dist;
      ASSERT_EQ(ours.nearestKSearch(query, k, idx, dist), k);
      for (uindex_t j = 0; j < k; ++j) {
        ASSERT_EQ(idx[j], by_distance[j].second) << "neighbour " << j;
        ASSERT_FLOAT_EQ(dist[j], by_distance[j].first);
      }

      const double radius = 3.0 * u(rng);
      Indices within;
      for (const auto& [d, i] : by_distance)
        if (d <= radius * radius) within.push_back(i);
      ASSERT_EQ(ours.radiusSearch(query, radius, idx, dist), within.size());
      for (std::size_t j = 0; j < idx.size(); ++j)
        ASSERT_FLOAT_EQ(dist[j], squaredDistance((*cloud)[idx[j]], query));
      std::sort(idx.begin(), idx.end());
      std::sort(within.begin(), within.end());
      ASSERT_EQ(idx, within) << "radius " << radius;
      ASSERT_EQ(ours.radiusSearch(query, radius, idx, dist, 5), std::min<std::size_t>(5, within.size()));
      for (const auto i : idx) ASSERT_TRUE(std::binary_search(within.begin(), within.end(), i));

      const Eigen::Vector3f box_lo(4 * u(rng), 4 * u(rng), 4 * u(rng));
      const Eigen::Vector3f box_hi(5 + 4 * u(rng), 5 + 4 * u(rng), 5 + 4 * u(rng));
      Indices in_box, pcl_in_box;
      for (std::size_t i = 0; i < cloud->size(); ++i) {
        const Eigen::Vector3f p = (*cloud)[i].getVector3fMap();
        if ((p.array() >= box_lo.array()).all() && (p.array() <= box_hi.array()).all())
          in_box.push_back(pcl::index_t(i));
      }
      ours.boxSearch(box_lo, box_hi, idx);
      ref.boxSearch(box_lo, box_hi, pcl_in_box);
      ASSERT_EQ(idx, pcl_in_box);
      std::sort(idx.begin(), idx.end());
      ASSERT_EQ(idx, in_box);

      // The approximate search returns a real point at its true distance, never nearer than the nearest.
      pcl::index_t found = -1, pcl_found = -1;
      float found_dist = -1, pcl_dist = -1;
      ours.approxNearestSearch(query, found, found_dist);
      ref.approxNearestSearch(query, pcl_found, pcl_dist);
      ASSERT_EQ(found, pcl_found);
      ASSERT_GE(found, 0);
      ASSERT_FLOAT_EQ(found_dist, squaredDistance((*cloud)[found], query));
      ASSERT_GE(found_dist, by_distance[0].first);
      approx_exact += found == by_distance[0].second;
    }
    EXPECT_GT(approx_exact, 0u) << "the approximate search finds the nearest point at times";
  }
}

TEST(OctreeSearch, RayThroughPointsFindsTheirVoxels) {
  const double res = 0.1;
  pcl::octree::OctreePointCloudSearch<PointXYZ> ref(res);
  pcl::fot::OctreePointCloudSearch<PointXYZ> ours(res);
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  int rays = 0;
  while (rays < 40) {
    // Four points on one ray, from a target inside [0, 10]^3 back towards an origin in [0, 12]^3 (points
    // beyond 10 grow the box); a quarter of the way apart, so each has its own voxel.
    const Eigen::Vector3f target(10 * u(rng), 10 * u(rng), 10 * u(rng)),
        origin(12 * u(rng), 12 * u(rng), 12 * u(rng));
    const Eigen::Vector3f direction = target - origin;
    if (0.25f * direction.norm() < 4 * res) continue;
    ++rays;
    Cloud::Ptr cloud(new Cloud);
    for (const float t : {1.0f, 0.75f, 0.5f, 0.25f}) {
      const Eigen::Vector3f p = origin + t * direction;
      cloud->emplace_back(p.x(), p.y(), p.z());
    }
    ours.deleteTree(), ours.defineBoundingBox(0, 0, 0, 10, 10, 10), ours.setInputCloud(cloud);
    ref.deleteTree(), ref.defineBoundingBox(0, 0, 0, 10, 10, 10), ref.setInputCloud(cloud);
    ours.addPointsFromInputCloud(), ref.addPointsFromInputCloud();

    pcl::fot::OctreePointCloudSearch<PointXYZ>::AlignedPointTVector centres;
    Indices indices, pcl_indices;
    ASSERT_EQ(ours.getIntersectedVoxelCenters(origin, direction, centres), 4u) << "ray " << rays;
    ASSERT_EQ(ours.getIntersectedVoxelIndices(origin, direction, indices), 4u);
    ref.getIntersectedVoxelIndices(origin, direction, pcl_indices);
    EXPECT_EQ(indices, pcl_indices);
    // Near to far: each centre is its point's voxel, and both grow further along the ray.
    for (std::size_t j = 0; j < 4; ++j) {
      const Eigen::Vector3f p = (*cloud)[indices[j]].getVector3fMap(), c = centres[j].getVector3fMap();
      ASSERT_LE((c - p).cwiseAbs().maxCoeff(), 0.5 * res + 1e-5) << "voxel " << j;
      if (j > 0) {
        ASSERT_GT((p - origin).dot(direction),
                  ((*cloud)[indices[j - 1]].getVector3fMap() - origin).dot(direction));
        ASSERT_GT((c - origin).dot(direction), (centres[j - 1].getVector3fMap() - origin).dot(direction));
      }
    }
    // Only the first voxel: the point nearest to the origin.
    ASSERT_EQ(ours.getIntersectedVoxelCenters(origin, direction, centres, 1), 1u);
    ASSERT_EQ(ours.getIntersectedVoxelIndices(origin, direction, indices, 1), 1u);
    for (const auto& p : *cloud)
      ASSERT_GE((p.getVector3fMap() - origin).norm(),
                ((*cloud)[indices[0]].getVector3fMap() - origin).norm());
  }
}

// ---- Bounding box

TEST(BoundingBox, DefinedBoxCoversTheRequestAndRoundTrips) {
  const double res = 7.25;
  pcl::octree::OctreePointCloud<PointXYZ> ref(res);
  pcl::fot::OctreePointCloud<PointXYZ> ours(res);
  // 20.5 voxels asked for: the cube of 2^5 voxels around them, the smallest that holds them.
  ref.defineBoundingBox(0, 0, 0, 20.5 * res, 20.5 * res, 20.5 * res);
  ours.defineBoundingBox(0, 0, 0, 20.5 * res, 20.5 * res, 20.5 * res);
  expectSameBox(ref, ours);
  double lo[3], hi[3];
  box(ours, lo, hi);
  EXPECT_EQ(ours.getTreeDepth(), 5u);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(lo[a], 0.0);
    EXPECT_GE(hi[a], 20.5 * res);
    EXPECT_NEAR(hi[a] - lo[a], 32 * res, 1e-9);
  }
  // A box read back and defined again stays as it was, also far from the origin where doubles are coarse.
  for (const double at : {2e7, -3e6, 0.0}) {
    SCOPED_TRACE(::testing::Message() << "near " << at);
    pcl::octree::OctreePointCloud<PointXYZ> ref2(res);
    pcl::fot::OctreePointCloud<PointXYZ> ours2(res);
    ref2.defineBoundingBox(at - 45 * res, at - 40 * res, at - 45 * res, at - 5 * res, at - 7 * res,
                           at - 9 * res);
    ours2.defineBoundingBox(at - 45 * res, at - 40 * res, at - 45 * res, at - 5 * res, at - 7 * res,
                            at - 9 * res);
    expectSameBox(ref2, ours2);
    box(ours2, lo, hi);
    const uindex_t depth = ours2.getTreeDepth();
    ours2.defineBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    ref2.defineBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    EXPECT_EQ(ours2.getTreeDepth(), depth);
    double lo2[3], hi2[3];
    box(ours2, lo2, hi2);
    EXPECT_TRUE(std::equal(lo, lo + 3, lo2) && std::equal(hi, hi + 3, hi2));
    expectSameBox(ref2, ours2);
  }
}

TEST(BoundingBox, PointsOutsideGrowItAndDeleteTreeResetsIt) {
  pcl::octree::OctreePointCloud<PointXYZ> ref(0.25);
  pcl::fot::OctreePointCloud<PointXYZ> ours(0.25);
  Cloud::Ptr ref_cloud(new Cloud), ours_cloud(new Cloud);
  ref.defineBoundingBox(0, 0, 0, 2, 2, 2);
  ours.defineBoundingBox(0, 0, 0, 2, 2, 2);
  ref.setInputCloud(ref_cloud);
  ours.setInputCloud(ours_cloud);
  std::mt19937 rng(14);
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  for (int i = 0; i < 20; ++i) {
    const PointXYZ p(u(rng), u(rng), u(rng));
    ref.addPointToCloud(p, ref_cloud);
    ours.addPointToCloud(p, ours_cloud);
  }
  const uindex_t depth = ours.getTreeDepth();
  for (const PointXYZ& far :
       {PointXYZ(-3.0f, 1.0f, 1.0f), PointXYZ(1.0f, 9.0f, 1.0f), PointXYZ(1.0f, 1.0f, -0.01f)}) {
    SCOPED_TRACE(::testing::Message() << "after (" << far.x << ", " << far.y << ", " << far.z << ")");
    ref.addPointToCloud(far, ref_cloud);
    ours.addPointToCloud(far, ours_cloud);
    expectSameBox(ref, ours);
    double lo[3], hi[3];
    box(ours, lo, hi);
    const Eigen::Vector3f p = far.getVector3fMap();
    for (int a = 0; a < 3; ++a) EXPECT_TRUE(lo[a] <= p[a] && p[a] < hi[a]) << "axis " << a;
    for (const auto& q : *ours_cloud) ASSERT_TRUE(ours.isVoxelOccupiedAtPoint(q)) << "earlier points stay";
    EXPECT_EQ(walk(ours.begin(), ours.end()), walk(ref.begin(), ref.end()));
  }
  EXPECT_GT(ours.getTreeDepth(), depth);
  Indices all;
  for (auto it = ours.leaf_depth_begin(); it != ours.leaf_depth_end(); ++it)
    it.getLeafContainer().getPointIndices(all);
  std::sort(all.begin(), all.end());
  EXPECT_EQ(all.size(), 23u);
  EXPECT_EQ(std::adjacent_find(all.begin(), all.end()), all.end());

  ref.deleteTree();
  ours.deleteTree();
  EXPECT_EQ(ours.getLeafCount(), 0u);
  EXPECT_TRUE(ours.leaf_depth_begin() == ours.leaf_depth_end());
  EXPECT_EQ(walk(ours.begin(), ours.end()), walk(ref.begin(), ref.end())) << "PCL keeps its root";
  expectSameBox(ref, ours);
  ref.defineBoundingBox(5, 5, 5, 6, 6, 6);
  ours.defineBoundingBox(5, 5, 5, 6, 6, 6);
  expectSameBox(ref, ours);
  EXPECT_FALSE(ours.isVoxelOccupiedAtPoint(PointXYZ(5.5f, 5.5f, 5.5f)));
}

// Not in PCL's suite: the rest of pcl::octree's public API that code written for it calls.
TEST(OctreeApi, LeavesByKeyNodeIdsAndResetAsPcls) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  Cloud::Ptr cloud(new Cloud);
  for (int i = 0; i < 300; ++i) cloud->push_back(PointXYZ(u(rng), u(rng), u(rng)));
  pcl::octree::OctreePointCloud<PointXYZ> ref(0.125);
  pcl::fot::OctreePointCloud<PointXYZ> ours(0.125);
  EXPECT_EQ(ours.findLeaf(0, 0, 0), nullptr) << "no box yet";
  EXPECT_EQ(ours.createLeaf(0, 0, 0), nullptr) << "no box yet";
  ref.setInputCloud(cloud);
  ref.addPointsFromInputCloud();
  ours.setInputCloud(cloud);
  ours.addPointsFromInputCloud();
  ASSERT_EQ(ours.getTreeDepth(), ref.getTreeDepth());
  const uindex_t n = uindex_t(1) << ours.getTreeDepth();

  // findLeaf by key: the same leaves, with the same points; nothing beyond the box.
  std::size_t found = 0;
  std::array<uindex_t, 3> empty{n, n, n}, held{n, n, n};
  for (uindex_t x = 0; x < n; ++x)
    for (uindex_t y = 0; y < n; ++y)
      for (uindex_t z = 0; z < n; ++z) {
        auto* a = ref.findLeaf(x, y, z);
        auto* b = ours.findLeaf(x, y, z);
        ASSERT_EQ(a == nullptr, b == nullptr) << x << " " << y << " " << z;
        (a ? held : empty) = {x, y, z};
        if (!a) continue;
        ++found;
        EXPECT_EQ(a->getPointIndicesVector(), b->getPointIndicesVector());
      }
  EXPECT_EQ(found, ref.getLeafCount());
  ASSERT_LT(empty[0], n);
  EXPECT_EQ(ours.findLeaf(n, 0, 0), nullptr);

  // createLeaf: an existing leaf's container, or a new empty leaf; nothing beyond the box.
  EXPECT_EQ(ours.createLeaf(held[0], held[1], held[2]), ours.findLeaf(held[0], held[1], held[2]));
  ref.createLeaf(empty[0], empty[1], empty[2]);
  auto* fresh = ours.createLeaf(empty[0], empty[1], empty[2]);
  ASSERT_NE(fresh, nullptr);
  EXPECT_EQ(fresh->getSize(), 0u);
  EXPECT_EQ(fresh, ours.findLeaf(empty[0], empty[1], empty[2]));
  EXPECT_TRUE(ours.existLeaf(empty[0], empty[1], empty[2]));
  EXPECT_EQ(ours.createLeaf(0, n, 0), nullptr);
  EXPECT_EQ(ours.getLeafCount(), ref.getLeafCount());
  EXPECT_EQ(ours.getBranchCount(), ref.getBranchCount());

  // Iterators: PCL's node ids and operator*, a null node at the end, and reset to the first node.
  auto a = ref.depth_begin();
  auto b = ours.depth_begin();
  for (; a != ref.depth_end(); ++a, ++b) {
    ASSERT_TRUE(b != ours.depth_end());
    EXPECT_EQ(b.getNodeID(), a.getNodeID());
    EXPECT_EQ((*b)->getNodeType(), (*a)->getNodeType());
  }
  EXPECT_TRUE(b == ours.depth_end());
  EXPECT_EQ(*b, nullptr);
  auto leaf = ours.leaf_breadth_begin();
  auto ref_leaf = ref.leaf_breadth_begin();
  for (int i = 0; i < 5; ++i) ++leaf, ++ref_leaf;
  leaf.reset();
  ref_leaf.reset();
  EXPECT_TRUE(leaf == ours.leaf_breadth_begin());
  EXPECT_EQ(leaf.getNodeID(), ref_leaf.getNodeID());
  // Branches hold nothing here: they share one empty container.
  auto branch = ours.begin();
  ASSERT_TRUE(branch.isBranchNode());
  auto* first = &branch.getBranchContainer();
  ++branch;
  ASSERT_TRUE(branch.isBranchNode());
  EXPECT_EQ(&branch.getBranchContainer(), first);
}

// Not in PCL's suite: setTreeDepth and setMaxVoxelIndex set the depth until a box is defined, which sets it
// again; ours refuses them afterwards, where PCL would change the depth without the box.
TEST(OctreeApi, TreeDepthAndMaxVoxelIndexBeforeTheBoxAsPcls) {
  pcl::octree::OctreePointCloud<PointXYZ> ref(0.1);
  pcl::fot::OctreePointCloud<PointXYZ> ours(0.1);
  for (uindex_t depth : {1u, 7u, 29u}) {
    ref.setTreeDepth(depth);
    ours.setTreeDepth(depth);
    EXPECT_EQ(ours.getTreeDepth(), ref.getTreeDepth());
  }
  for (uindex_t index : {2u, 3u, 1000u, 1024u, 1025u, 1u << 29}) {
    ref.setMaxVoxelIndex(index);
    ours.setMaxVoxelIndex(index);
    EXPECT_EQ(ours.getTreeDepth(), ref.getTreeDepth()) << index;
  }
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  Cloud::Ptr cloud(new Cloud);
  for (int i = 0; i < 100; ++i) cloud->push_back(PointXYZ(u(rng), u(rng), u(rng)));
  ref.setInputCloud(cloud);
  ref.addPointsFromInputCloud();
  ours.setInputCloud(cloud);
  ours.addPointsFromInputCloud();
  const uindex_t depth = ours.getTreeDepth();
  EXPECT_EQ(depth, ref.getTreeDepth()) << "the box sets the depth again";
  EXPECT_EQ(ours.getLeafCount(), ref.getLeafCount());

  for (uindex_t bad : {0u, 30u, depth + 1}) ours.setTreeDepth(bad);
  for (uindex_t bad : {0u, 1u, (1u << 29) + 1}) ours.setMaxVoxelIndex(bad);
  EXPECT_EQ(ours.getTreeDepth(), depth) << "refused: out of range, or the box is defined";
  EXPECT_EQ(ours.getLeafCount(), ref.getLeafCount());
  ref.deleteTree();
  ours.deleteTree();
  ref.setTreeDepth(5);
  ours.setTreeDepth(5);
  EXPECT_EQ(ours.getTreeDepth(), ref.getTreeDepth()) << "an emptied octree has no box";
}
