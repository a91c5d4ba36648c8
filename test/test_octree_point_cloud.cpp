// pcl::fot::OctreePointCloud gives the same answers as pcl::octree for the same calls on real scans.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>

#include <pcl/common/point_tests.h>  // PCL 1.13's occupancy header uses isFinite without including it
#include <pcl/octree/octree_pointcloud_occupancy.h>
#include <pcl/octree/octree_search.h>

#include <pcl_fot/pcl/octree/octree_point_cloud.h>

#include "scan_data.h"

using pcl::PointXYZ;
using Cloud = pcl::PointCloud<PointXYZ>;
using Reference = pcl::octree::OctreePointCloudOccupancy<PointXYZ>;
using Ours = pcl::fot::OctreePointCloud<PointXYZ>;

namespace {

void expectSameCentres(const Reference::AlignedPointTVector& a, const Ours::AlignedPointTVector& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].x, b[i].x) << "centre " << i;
    ASSERT_EQ(a[i].y, b[i].y) << "centre " << i;
    ASSERT_EQ(a[i].z, b[i].z) << "centre " << i;
  }
}

/** Walks an iterator of each octree to its end, node by node: key, depth, kind, children and bounds. */
template <typename Begin, typename End>
void expectSameNodes(Reference& ref, const Ours& ours, Begin begin, End end, const std::string& what) {
  auto rt = begin(ref);
  auto ot = begin(ours);
  std::size_t n = 0;
  for (; rt != end(ref); ++rt, ++ot, ++n) {
    ASSERT_TRUE(ot != end(ours)) << what << ": ours ends after " << n << " nodes";
    ASSERT_EQ(rt.getCurrentOctreeKey(), ot.getCurrentOctreeKey()) << what << ", node " << n;
    ASSERT_EQ(rt.getCurrentOctreeDepth(), ot.getCurrentOctreeDepth()) << what << ", node " << n;
    ASSERT_EQ(rt.isBranchNode(), ot.isBranchNode()) << what << ", node " << n;
    ASSERT_EQ(rt.isLeafNode(), ot.isLeafNode()) << what << ", node " << n;
    ASSERT_EQ(rt.getNodeConfiguration(), ot.getNodeConfiguration()) << what << ", node " << n;
    Eigen::Vector3f rmin, rmax, omin, omax;
    ref.getVoxelBounds(rt, rmin, rmax);
    ours.getVoxelBounds(ot, omin, omax);
    ASSERT_EQ(rmin, omin) << what << ", node " << n;
    ASSERT_EQ(rmax, omax) << what << ", node " << n;
  }
  EXPECT_TRUE(ot == end(ours)) << what << ": ours goes on after " << n << " nodes";
}

/** Every PCL iterator, at the full depth and cut short. */
void expectSameIterators(Reference& ref, const Ours& ours) {
  const pcl::uindex_t depth = ref.getTreeDepth();
  for (const pcl::uindex_t max : {pcl::uindex_t(0), pcl::uindex_t(1), depth / 2, depth - 1, depth + 2}) {
    const std::string at = " to depth " + std::to_string(max);
    expectSameNodes(
        ref, ours, [&](auto& t) { return t.begin(max); }, [](auto& t) { return t.end(); },
        "depth-first" + at);
    expectSameNodes(
        ref, ours, [&](auto& t) { return t.breadth_begin(max); }, [](auto& t) { return t.breadth_end(); },
        "breadth-first" + at);
    expectSameNodes(
        ref, ours, [&](auto& t) { return t.leaf_depth_begin(max); },
        [](auto& t) { return t.leaf_depth_end(); }, "leaves" + at);
  }
  for (const pcl::uindex_t d : {pcl::uindex_t(0), pcl::uindex_t(1), depth / 2, depth, depth + 1})
    expectSameNodes(
        ref, ours, [&](auto& t) { return t.fixed_depth_begin(d); },
        [](auto& t) { return t.fixed_depth_end(); }, "fixed depth " + std::to_string(d));
  std::size_t nodes = 0, branches = 0;
  for (auto it = ours.begin(); it != ours.end(); ++it) {
    ++nodes;
    branches += it.isBranchNode();
  }
  EXPECT_EQ(nodes, ref.getBranchCount() + ref.getLeafCount());
  EXPECT_EQ(branches, ref.getBranchCount());
}

/** Everything the two octrees can be asked without changing them. */
void expectSameState(Reference& ref, const Ours& ours) {
  double r[6], o[6];
  ref.getBoundingBox(r[0], r[1], r[2], r[3], r[4], r[5]);
  ours.getBoundingBox(o[0], o[1], o[2], o[3], o[4], o[5]);
  for (int i = 0; i < 6; ++i) ASSERT_EQ(r[i], o[i]) << "bounding box value " << i;
  ASSERT_EQ(ref.getTreeDepth(), ours.getTreeDepth());
  ASSERT_EQ(ref.getResolution(), ours.getResolution());
  ASSERT_EQ(ref.getLeafCount(), ours.getLeafCount());
  ASSERT_EQ(ref.getBranchCount(), ours.getBranchCount());
  for (pcl::uindex_t d = 0; d <= ref.getTreeDepth(); ++d) {
    ASSERT_EQ(ref.getVoxelSquaredSideLen(d), ours.getVoxelSquaredSideLen(d));
    ASSERT_EQ(ref.getVoxelSquaredDiameter(d), ours.getVoxelSquaredDiameter(d));
  }
  ASSERT_EQ(ref.getVoxelSquaredSideLen(), ours.getVoxelSquaredSideLen());
  ASSERT_EQ(ref.getVoxelSquaredDiameter(), ours.getVoxelSquaredDiameter());

  Reference::AlignedPointTVector a;
  Ours::AlignedPointTVector b;
  ASSERT_EQ(ref.getOccupiedVoxelCenters(a), ours.getOccupiedVoxelCenters(b));
  expectSameCentres(a, b);

  auto it = ref.leaf_depth_begin();
  auto jt = ours.leaf_depth_begin();
  std::size_t n = 0;
  for (; it != ref.leaf_depth_end() && jt != ours.leaf_depth_end(); ++it, ++jt, ++n) {
    ASSERT_EQ(it.getCurrentOctreeKey(), jt.getCurrentOctreeKey()) << "leaf " << n;
    ASSERT_EQ(it.getCurrentOctreeDepth(), jt.getCurrentOctreeDepth());
    Eigen::Vector3f rmin, rmax, omin, omax;
    ref.getVoxelBounds(it, rmin, rmax);
    ours.getVoxelBounds(jt, omin, omax);
    ASSERT_EQ(rmin, omin);
    ASSERT_EQ(rmax, omax);
  }
  EXPECT_TRUE(it == ref.leaf_depth_end());
  EXPECT_TRUE(jt == ours.leaf_depth_end());
  EXPECT_EQ(n, ref.getLeafCount());

  n = 0;
  auto bt = ours.leaf_breadth_begin();
  for (auto rt = ref.leaf_breadth_begin(); rt != ref.leaf_breadth_end(); ++rt, ++bt, ++n) {
    ASSERT_TRUE(bt != ours.leaf_breadth_end());
    ASSERT_EQ(rt.getCurrentOctreeKey(), bt.getCurrentOctreeKey()) << "breadth-first leaf " << n;
  }
  EXPECT_TRUE(bt == ours.leaf_breadth_end());
  EXPECT_EQ(n, ref.getLeafCount());

  expectSameIterators(ref, ours);
  // Leaves by key: every voxel, its neighbours and keys beyond the box, where PCL drops the high bits.
  const pcl::uindex_t side = pcl::uindex_t(1) << ref.getTreeDepth();
  for (auto it = ours.leaf_depth_begin(); it != ours.leaf_depth_end(); ++it) {
    const pcl::octree::OctreeKey& k = it.getCurrentOctreeKey();
    ASSERT_TRUE(ref.existLeaf(k.x, k.y, k.z));
    ASSERT_TRUE(ours.existLeaf(k.x, k.y, k.z));
    const pcl::uindex_t nx = (k.x + 1) % side;
    ASSERT_EQ(ref.existLeaf(nx, k.y, k.z), ours.existLeaf(nx, k.y, k.z));
    ASSERT_FALSE(ours.existLeaf(k.x + side, k.y, k.z));
  }
}

/** Every cloud point and random points around the box, through all three overloads. */
void expectSameOccupancyQueries(const Reference& ref, const Ours& ours, const Cloud& cloud) {
  for (pcl::index_t i = 0; i < pcl::index_t(cloud.size()); i += 3) {
    if (!pcl::isFinite(cloud[i])) continue;
    ASSERT_EQ(ref.isVoxelOccupiedAtPoint(cloud[i]), ours.isVoxelOccupiedAtPoint(cloud[i])) << "point " << i;
    ASSERT_EQ(ref.isVoxelOccupiedAtPoint(i), ours.isVoxelOccupiedAtPoint(i));
  }
  double lo[3], hi[3];
  ref.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  std::mt19937 rng(17);
  for (int i = 0; i < 20000; ++i) {
    double p[3];
    for (int a = 0; a < 3; ++a) p[a] = std::uniform_real_distribution<double>(lo[a] - 1.0, hi[a] + 1.0)(rng);
    ASSERT_EQ(ref.isVoxelOccupiedAtPoint(p[0], p[1], p[2]), ours.isVoxelOccupiedAtPoint(p[0], p[1], p[2]));
  }
}

Cloud::Ptr scan(const std::string& name) {
  Cloud::Ptr raw = pcl_fot_test::loadScan(name);
  Cloud::Ptr finite(new Cloud);
  for (const auto& p : *raw)
    if (pcl::isFinite(p)) finite->push_back(p);
  return finite;
}

}  // namespace

PCL_FOT_SCAN_TESTS(OctreePointCloudOnScans);

TEST_P(OctreePointCloudOnScans, GrowsItsBoxLikePclFromTheFirstPoint) {
  for (const auto& [name, res] : std::vector<std::pair<std::string, double>>{
           {"room_scan1.pcd", 0.05}, {"kinect_capture0001.pcd", 0.01}}) {
    SCOPED_TRACE(name);
    const Cloud::Ptr cloud = pcl_fot_test::loadScan(name);  // NaN points included: both skip them
    Reference ref(res);
    Ours ours(res);
    ref.setOccupiedVoxelsAtPointsFromCloud(cloud);
    ours.setOccupiedVoxelsAtPointsFromCloud(cloud);
    ref.setInputCloud(cloud);
    ours.setInputCloud(cloud);
    expectSameState(ref, ours);
    expectSameOccupancyQueries(ref, ours, *cloud);
  }
}

TEST_P(OctreePointCloudOnScans, DefinedBoundingBoxAndInputCloud) {
  const Cloud::Ptr cloud = scan("room_scan2.pcd");
  auto indices = std::make_shared<pcl::Indices>();
  for (pcl::index_t i = 0; i < pcl::index_t(cloud->size()); i += 2) indices->push_back(i);
  Reference ref(0.05);
  Ours ours(0.05);
  ref.setInputCloud(cloud, indices);
  ours.setInputCloud(cloud, indices);
  EXPECT_EQ(ours.getInputCloud(), cloud);
  EXPECT_EQ(ours.getIndices(), indices);
  ref.defineBoundingBox();
  ours.defineBoundingBox();
  ref.addPointsFromInputCloud();
  ours.addPointsFromInputCloud();
  expectSameState(ref, ours);
  expectSameOccupancyQueries(ref, ours, *cloud);
  // Redefining the box with the values it reports keeps it (PCL's Octree_Pointcloud_Bounds test).
  double b[6];
  ours.getBoundingBox(b[0], b[1], b[2], b[3], b[4], b[5]);
  Ours again(0.05);
  again.defineBoundingBox(b[0], b[1], b[2], b[3], b[4], b[5]);
  double c[6];
  again.getBoundingBox(c[0], c[1], c[2], c[3], c[4], c[5]);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(b[i], c[i]);
  EXPECT_EQ(again.getTreeDepth(), ours.getTreeDepth());
}

TEST_P(OctreePointCloudOnScans, OtherBoundingBoxForms) {
  const Cloud::Ptr cloud = scan("kinect_capture0002.pcd");
  for (int form = 0; form < 2; ++form) {
    Reference ref(0.02);
    Ours ours(0.02);
    if (form == 0) {
      ref.defineBoundingBox(4.0);
      ours.defineBoundingBox(4.0);
    } else {
      ref.defineBoundingBox(2.0, -1.5, 3.5);
      ours.defineBoundingBox(2.0, -1.5, 3.5);
    }
    ref.setOccupiedVoxelsAtPointsFromCloud(cloud);
    ours.setOccupiedVoxelsAtPointsFromCloud(cloud);
    expectSameState(ref, ours);
  }
}

TEST_P(OctreePointCloudOnScans, GrowingAnEmptyBoxAndDeletingVoxels) {
  // The box starts far from the data, so it grows while the octree holds no voxel: PCL keeps the empty old
  // roots as branches, and deletions prune them.
  const Cloud::Ptr cloud = scan("room_scan1.pcd");
  Reference ref(0.05);
  Ours ours(0.05);
  ref.defineBoundingBox(20.0, 20.0, 20.0, 20.3, 20.3, 20.3);
  ours.defineBoundingBox(20.0, 20.0, 20.0, 20.3, 20.3, 20.3);
  PointXYZ far(-7.0f, -9.0f, 1.0f);
  ref.setOccupiedVoxelAtPoint(far);
  ours.setOccupiedVoxelAtPoint(far);
  expectSameState(ref, ours);
  ref.setOccupiedVoxelsAtPointsFromCloud(cloud);
  ours.setOccupiedVoxelsAtPointsFromCloud(cloud);
  expectSameState(ref, ours);
  for (std::size_t i = 0; i < cloud->size(); i += 5) {
    ref.deleteVoxelAtPoint((*cloud)[i]);
    ours.deleteVoxelAtPoint((*cloud)[i]);
  }
  expectSameState(ref, ours);
  std::vector<pcl::octree::OctreeKey> keys;
  for (auto it = ours.leaf_depth_begin(); it != ours.leaf_depth_end(); ++it)
    keys.push_back(it.getCurrentOctreeKey());
  for (std::size_t i = 0; i < keys.size(); i += 7) {
    ref.removeLeaf(keys[i].x, keys[i].y, keys[i].z);
    ours.removeLeaf(keys[i].x, keys[i].y, keys[i].z);
  }
  const pcl::uindex_t side = pcl::uindex_t(1) << ours.getTreeDepth();
  ours.removeLeaf(keys[1].x + side, keys[1].y, keys[1].z);  // beyond the box: nothing happens
  expectSameState(ref, ours);
  ref.deleteVoxelAtPoint(far);
  ours.deleteVoxelAtPoint(far);
  ref.deleteVoxelAtPoint(PointXYZ(20.1f, 20.1f, 20.1f));  // inside the empty old root: prunes it
  ours.deleteVoxelAtPoint(PointXYZ(20.1f, 20.1f, 20.1f));
  expectSameState(ref, ours);
  for (const auto& p : *cloud) {
    ref.deleteVoxelAtPoint(p);
    ours.deleteVoxelAtPoint(p);
  }
  expectSameState(ref, ours);
  EXPECT_EQ(ours.getLeafCount(), 0u);
}

TEST_P(OctreePointCloudOnScans, AddPointToCloudAndDeleteTree) {
  const Cloud::Ptr source = scan("kinect_capture0003.pcd");
  Cloud::Ptr a(new Cloud), b(new Cloud);
  auto ia = std::make_shared<pcl::Indices>(), ib = std::make_shared<pcl::Indices>();
  Reference ref(0.03);
  Ours ours(0.03);
  ref.setInputCloud(a, ia);
  ours.setInputCloud(b, ib);
  for (std::size_t i = 0; i < source->size(); i += 11) {
    ref.addPointToCloud((*source)[i], a, ia);
    ours.addPointToCloud((*source)[i], b, ib);
  }
  EXPECT_EQ(*ia, *ib);
  EXPECT_EQ(a->size(), b->size());
  expectSameState(ref, ours);
  ref.deleteTree();
  ours.deleteTree();
  expectSameState(ref, ours);
  ref.setOccupiedVoxelsAtPointsFromCloud(source);
  ours.setOccupiedVoxelsAtPointsFromCloud(source);
  expectSameState(ref, ours);

  // Points of the input cloud by index (PCL's tree would take a NaN point into its box: finite ones only).
  Reference ref2(0.03);
  Ours ours2(0.03);
  ref2.setInputCloud(source);
  ours2.setInputCloud(source);
  auto ja = std::make_shared<pcl::Indices>(), jb = std::make_shared<pcl::Indices>();
  for (pcl::uindex_t i = 0; i < source->size(); i += 13) {
    if (!pcl::isFinite((*source)[i])) continue;
    ref2.addPointFromCloud(i, ja);
    ours2.addPointFromCloud(i, jb);
  }
  ours2.addPointFromCloud(pcl::uindex_t(source->size()), jb);  // refused: nothing added, no index
  EXPECT_GT(ja->size(), 1000u);
  EXPECT_EQ(*ja, *jb);
  expectSameState(ref2, ours2);
}

namespace {

/**
 * Both ray answers list the same voxels in the same order, except where exact arithmetic (long double, on
 * the same float inputs) shows PCL wrong: every voxel only we list is one the ray passes, every voxel only
 * PCL lists is one it misses, up to grazes within 1e-9 of the ray's length where rounding decides.
 * (PCL 1.13 traverses in float, which misjudges near-axis-parallel rays by about 1e-6.)
 */
void expectSameRayAnswer(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, const double lo[3],
                         double res, const Reference::AlignedPointTVector& pcl_list,
                         const Ours::AlignedPointTVector& our_list) {
  using Cell = std::array<long, 3>;
  auto cell = [&](const PointXYZ& c) {
    return Cell{long(std::floor((c.x - lo[0]) / res)), long(std::floor((c.y - lo[1]) / res)),
                long(std::floor((c.z - lo[2]) / res))};
  };
  // How long (in ray parameter) the ray stays inside the cell; negative when it misses it.
  auto inside = [&](const Cell& k) {
    long double t0 = -1e30L, t1 = 1e30L;
    for (int a = 0; a < 3; ++a) {
      const long double c0 = lo[a] + (long double)k[a] * res, c1 = c0 + res, d = direction[a], o = origin[a];
      if (d == 0) {
        // A ray in a voxel's face plane (within rounding) grazes it, as the 1e-9 margins below allow.
        if (std::min(std::fabs(o - c0), std::fabs(o - c1)) <= 1e-9L * res) return 0.0L;
        if (o < c0 || o >= c1) return -1.0L;
        continue;
      }
      long double ta = (c0 - o) / d, tb = (c1 - o) / d;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    return t1 - t0;
  };
  std::vector<Cell> a, b;
  for (const auto& c : pcl_list) a.push_back(cell(c));
  for (const auto& c : our_list) b.push_back(cell(c));
  if (a == b) return;
  std::vector<Cell> common_a, common_b;
  for (const Cell& k : a) {
    if (std::find(b.begin(), b.end(), k) != b.end())
      common_a.push_back(k);
    else
      EXPECT_LT(double(inside(k)), 1e-9) << "PCL lists a voxel the ray passes, and we do not";
  }
  for (const Cell& k : b) {
    if (std::find(a.begin(), a.end(), k) != a.end())
      common_b.push_back(k);
    else
      EXPECT_GT(double(inside(k)), -1e-9) << "we list a voxel the ray misses";
  }
  EXPECT_EQ(common_a, common_b) << "the voxels both list come in the same order";
}

/** PCL's approximate segment walk, step by step, keeping the samples inside the box. */
Reference::AlignedPointTVector sampledCentres(const Ours& octree, const Eigen::Vector3f& from,
                                              const Eigen::Vector3f& to, float precision) {
  double lo[3], hi[3];
  octree.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  const double res = octree.getResolution();
  const float step = float(res) * precision;
  const Eigen::Vector3f direction = (to - from).normalized();
  const auto steps = std::max<std::size_t>(1, (to - from).norm() / step);
  Reference::AlignedPointTVector out;
  std::array<std::int64_t, 3> last{-1, -1, -1};
  auto add = [&](const Eigen::Vector3f& p) {
    std::array<std::int64_t, 3> key;
    for (int a = 0; a < 3; ++a) {
      if (p[a] < lo[a] || p[a] >= hi[a]) return;
      key[a] = std::int64_t((p[a] - lo[a]) / res);
    }
    if (key == last) return;
    last = key;
    out.emplace_back(float(lo[0] + (key[0] + 0.5) * res), float(lo[1] + (key[1] + 0.5) * res),
                     float(lo[2] + (key[2] + 0.5) * res));
  };
  for (std::size_t i = 0; i < steps; ++i) add(from + direction * step * float(i));
  add(to);
  return out;
}

}  // namespace

TEST_P(OctreePointCloudOnScans, SegmentsAndRays) {
  const Cloud::Ptr cloud = scan("room_scan1.pcd");
  Reference ref(0.05);
  Ours ours(0.05);
  ref.setOccupiedVoxelsAtPointsFromCloud(cloud);
  ours.setOccupiedVoxelsAtPointsFromCloud(cloud);
  double lo[3], hi[3];
  ref.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  // getIntersectedVoxelCenters belongs to PCL's search octree: the same box and points.
  pcl::octree::OctreePointCloudSearch<PointXYZ> search(0.05);
  search.defineBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  search.setInputCloud(cloud);
  search.addPointsFromInputCloud();
  Ours ours_same_box(0.05);
  ours_same_box.defineBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  ours_same_box.setOccupiedVoxelsAtPointsFromCloud(cloud);

  std::mt19937 rng(23);
  std::uniform_real_distribution<float> jitter(-1.0f, 1.0f);
  std::size_t hits = 0;
  for (std::size_t i = 0; i < cloud->size(); i += 97) {
    // Segments inside the box, where PCL's approximate walk is defined.
    const Eigen::Vector3f from(jitter(rng), jitter(rng), 0.5f * jitter(rng));
    const Eigen::Vector3f to = (*cloud)[i].getVector3fMap();
    Reference::AlignedPointTVector a;
    Ours::AlignedPointTVector b;
    ASSERT_EQ(ref.getApproxIntersectedVoxelCentersBySegment(from, to, a, 0.2f),
              ours.getApproxIntersectedVoxelCentersBySegment(from, to, b, 0.2f));
    expectSameCentres(a, b);
    // From 40 m outside the box to a scan point, and through it to 30 m beyond, where PCL's keys are not
    // defined: every step sampled, those outside the box left out.
    const Eigen::Vector3f outside = from + Eigen::Vector3f(-40.0f, 3.0f, 1.0f);
    const Eigen::Vector3f beyond = outside + (to - outside).normalized() * 70.0f;
    for (const auto& seg : {std::make_pair(outside, to), std::make_pair(outside, beyond)}) {
      b.clear();
      ours.getApproxIntersectedVoxelCentersBySegment(seg.first, seg.second, b, 0.2f);
      expectSameCentres(sampledCentres(ours, seg.first, seg.second, 0.2f), b);
    }

    // Rays at a scan point, from inside the room or from outside the box.
    const Eigen::Vector3f origin = i % 2 ? from : Eigen::Vector3f(float(lo[0]) - 3.0f, to.y(), to.z() + 0.3f);
    const Eigen::Vector3f direction = to - origin;
    for (pcl::uindex_t max_count : {0u, 1u}) {
      pcl::octree::OctreePointCloudSearch<PointXYZ>::AlignedPointTVector c;
      Ours::AlignedPointTVector d;
      search.getIntersectedVoxelCenters(origin, direction, c, max_count);
      ours_same_box.getIntersectedVoxelCenters(origin, direction, d, max_count);
      expectSameRayAnswer(origin, direction, lo, 0.05, c, d);
      hits += d.size();
    }
  }
  EXPECT_GT(hits, cloud->size() / 97) << "rays aimed at scan points hit at least their voxel";
}

TEST(OctreePointCloud, BadInputIsRefusedWithoutHarm) {
  EXPECT_THROW(Ours(0.0), std::invalid_argument);
  EXPECT_THROW(Ours(-1.0), std::invalid_argument);
  Ours ours(0.1);
  ours.setOccupiedVoxelAtPoint(PointXYZ(1, 2, 3));
  ours.setOccupiedVoxelAtPoint(PointXYZ(std::nanf(""), 0, 0));
  EXPECT_EQ(ours.getLeafCount(), 1u);
  double box[6];
  ours.getBoundingBox(box[0], box[1], box[2], box[3], box[4], box[5]);
  const pcl::uindex_t depth = ours.getTreeDepth();
  ours.setOccupiedVoxelAtPoint(PointXYZ(1e9f, 0, 0));  // beyond 2^29 cells of 10 cm
  EXPECT_EQ(ours.getLeafCount(), 1u);
  double after[6];
  ours.getBoundingBox(after[0], after[1], after[2], after[3], after[4], after[5]);
  EXPECT_TRUE(std::equal(box, box + 6, after)) << "the box did not grow towards the point refused";
  EXPECT_EQ(ours.getTreeDepth(), depth);
  EXPECT_TRUE(ours.isVoxelOccupiedAtPoint(PointXYZ(1, 2, 3)));
  ours.setResolution(0.2);  // refused: the octree is not empty
  EXPECT_EQ(ours.getResolution(), 0.1);
  Ours empty(0.1);
  empty.setResolution(1e31);  // refused: cell centres beyond float's range
  EXPECT_EQ(empty.getResolution(), 0.1);
  EXPECT_THROW(Ours(1e31), std::invalid_argument);
  EXPECT_FALSE(ours.isVoxelOccupiedAtPoint(pcl::index_t(5))) << "no input cloud";

  // Segments: not finite, or no positive precision, leave the list as it was; a very long one ends at once.
  Ours::AlignedPointTVector centres(2);
  const Eigen::Vector3f at(1, 2, 3), nan_point(std::nanf(""), 0, 0), inf_point(0, INFINITY, 0);
  EXPECT_EQ(ours.getApproxIntersectedVoxelCentersBySegment(at, nan_point, centres), 2u);
  EXPECT_EQ(ours.getApproxIntersectedVoxelCentersBySegment(nan_point, at, centres), 2u);
  EXPECT_EQ(ours.getApproxIntersectedVoxelCentersBySegment(inf_point, at, centres), 2u);
  for (float precision : {0.0f, -0.2f, std::nanf(""), INFINITY})
    EXPECT_EQ(ours.getApproxIntersectedVoxelCentersBySegment(at, at, centres, precision), 2u) << precision;
  EXPECT_EQ(
      ours.getApproxIntersectedVoxelCentersBySegment(at, at + Eigen::Vector3f(0.05f, 0, 0), centres, 1e-20f),
      2u)
      << "5e17 steps are refused";
  // Through the box from 100 km away: only the steps near the box are taken, with the same result.
  const Eigen::Vector3f way(0.6f, 0.0f, 0.8f);
  centres.clear();
  ours.getApproxIntersectedVoxelCentersBySegment(at - 1e5f * way, at + 1e5f * way, centres);
  expectSameCentres(sampledCentres(ours, at - 1e5f * way, at + 1e5f * way, 0.2f), centres);
  EXPECT_FALSE(centres.empty());
  // 1e11 steps: those near the box fall on floats 64 m apart, so it may list nothing, but it returns.
  centres.clear();
  ours.getApproxIntersectedVoxelCentersBySegment(Eigen::Vector3f(-1e9f, 2, 3), Eigen::Vector3f(1e9f, 2, 3),
                                                 centres);
  EXPECT_LE(centres.size(), 1u);
}

TEST(OctreePointCloud, APointOnTheBoxsFarFaceIsInItsLastVoxel) {
  // Padded to a cube of 64 voxels, this box ends 2e-16 m past 0, so x = 0 lies inside it, but
  // (0 - min_x) / res rounds to 64, one past its last voxel. pcl::octree fails an assertion on it (found by
  // fuzz_octree_point_cloud); the voxel that holds such a point is the last one.
  Ours ours(0.05);
  ours.defineBoundingBox(-2.75, 0.0, 0.0, -0.45, 0.05, 0.05);
  double box[6];
  ours.getBoundingBox(box[0], box[1], box[2], box[3], box[4], box[5]);
  ASSERT_EQ(ours.getTreeDepth(), 6u);
  ASSERT_GT(box[3], 0.0);
  ASSERT_EQ(pcl::uindex_t((0.0 - box[0]) / 0.05), 64u) << "the rounding this test is about";
  const PointXYZ p(0, 0, 0);
  ours.setOccupiedVoxelAtPoint(p);
  EXPECT_TRUE(ours.isVoxelOccupiedAtPoint(p));
  ASSERT_EQ(ours.getLeafCount(), 1u);
  auto leaf = ours.leaf_depth_begin();
  EXPECT_EQ(leaf.getCurrentOctreeKey().x, 63u);
  Eigen::Vector3f lo, hi;
  ours.getVoxelBounds(leaf, lo, hi);
  EXPECT_LT(lo.x(), 0.0f);
  EXPECT_LE(hi.x(), box[3] + 1e-6);
  Ours::AlignedPointTVector centres;
  ASSERT_EQ(ours.getOccupiedVoxelCenters(centres), 1u);
  EXPECT_LT(centres[0].x, box[3]);
  ours.deleteVoxelAtPoint(p);
  EXPECT_EQ(ours.getLeafCount(), 0u);
}

TEST(OctreePointCloudIterators, CompareAsPclsDo) {
  Cloud::Ptr cloud(new Cloud), other(new Cloud);
  for (int i = 0; i < 50; ++i) {
    cloud->push_back(PointXYZ(0.1f * float(i % 7), 0.13f * float(i % 5), 0.07f * float(i)));
    other->push_back(PointXYZ(0.2f * float(i % 3), 0.1f * float(i), 0.05f));
  }
  Reference ref_a(0.1), ref_b(0.1);
  Ours a(0.1), b(0.1);
  ref_a.setInputCloud(cloud), ref_b.setInputCloud(other), a.setInputCloud(cloud), b.setInputCloud(other);
  ref_a.addPointsFromInputCloud(), ref_b.addPointsFromInputCloud(), a.addPointsFromInputCloud();
  b.addPointsFromInputCloud();
  // The same answers as pcl::octree, and the ones the issue names: true, true, false.
  EXPECT_EQ(a.begin() == a.begin(), ref_a.begin() == ref_a.begin());
  EXPECT_TRUE(a.begin() == a.begin());
  EXPECT_EQ(a.leaf_depth_begin() == a.leaf_depth_begin(),
            ref_a.leaf_depth_begin() == ref_a.leaf_depth_begin());
  EXPECT_TRUE(a.leaf_depth_begin() == a.leaf_depth_begin());
  EXPECT_EQ(a.end() == b.end(), ref_a.end() == ref_b.end());
  EXPECT_FALSE(a.end() == b.end());
  EXPECT_EQ(a.begin() == b.begin(), ref_a.begin() == ref_b.begin());
  EXPECT_EQ(a.begin() == a.end(), ref_a.begin() == ref_a.end());
  EXPECT_EQ(a.begin(2) == a.begin(), ref_a.begin(2) == ref_a.begin()) << "another maximum depth";
  // Walked in step, the iterators agree at every node and reach the end together.
  auto it = a.begin(), jt = a.begin();
  auto rt = ref_a.begin(), st = ref_a.begin();
  ++jt, ++st;
  EXPECT_EQ(it == jt, rt == st);
  for (; rt != ref_a.end(); ++rt, ++it) ASSERT_TRUE(it != a.end());
  EXPECT_TRUE(it == a.end());
  EXPECT_TRUE(it == it);
}

namespace {

/**
 * The occupied voxels a ray crosses, cell by cell, each cell's exit computed from its index as the octree's
 * walk computes it; that walk jumps over empty octants instead, and must land where these steps land.
 */
std::vector<std::array<long, 3>> voxelsStepByStep(const Ours& octree, const Eigen::Vector3f& origin,
                                                  const Eigen::Vector3f& direction) {
  double lo[3], hi[3];
  octree.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  const double res = octree.getResolution(), norm = direction.cast<double>().norm();
  const long cells = 1L << octree.getTreeDepth();
  double dir[3], t_in = 0.0, t_out = INFINITY;
  for (int a = 0; a < 3; ++a) {
    dir[a] = double(direction[a]) / norm;
    if (dir[a] == 0.0) {
      if (origin[a] < lo[a] || origin[a] >= hi[a]) return {};
      continue;
    }
    const double t0 = (lo[a] - origin[a]) / dir[a], t1 = (hi[a] - origin[a]) / dir[a];
    t_in = std::max(t_in, std::min(t0, t1));
    t_out = std::min(t_out, std::max(t0, t1));
  }
  if (t_in >= t_out) return {};
  std::array<long, 3> k;
  for (int a = 0; a < 3; ++a)
    k[a] = long(std::clamp(std::floor((origin[a] + t_in * dir[a] - lo[a]) / res), 0.0, double(cells - 1)));
  std::vector<std::array<long, 3>> out;
  while (std::all_of(k.begin(), k.end(), [&](long c) { return c >= 0 && c < cells; })) {
    if (octree.existLeaf(pcl::uindex_t(k[0]), pcl::uindex_t(k[1]), pcl::uindex_t(k[2]))) out.push_back(k);
    int exit = 0;
    double t_exit = INFINITY;
    for (int a = 0; a < 3; ++a) {
      if (dir[a] == 0.0) continue;
      const double t = ((double(k[a]) + (dir[a] > 0.0 ? 1.0 : 0.0)) * res - (origin[a] - lo[a])) / dir[a];
      if (t <= t_exit) exit = a, t_exit = t;  // at one distance z goes first, then y
    }
    k[exit] += dir[exit] > 0.0 ? 1 : -1;
  }
  return out;
}

}  // namespace

TEST(OctreePointCloud, RaysJumpOverTheEmptyPartsOfABoxMuchLargerThanTheCloud) {
  // A 2 m cloud, with a lattice on voxel corners for rays that tie, in a box of 2^14 voxels a side: the walk
  // jumps over empty octants and over the box around the octree's cells. It lists what steps cell by cell
  // list, and what PCL's walk lists (up to voxels a ray grazes).
  std::mt19937 rng(41);
  const Cloud::Ptr cloud = pcl_fot_test::randomCloud(rng, 2000, 2.0f);
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y) cloud->emplace_back(0.25f * x, 0.25f * y, 1.0f);
  const double res = 0.05;
  Ours ours(res);
  ours.defineBoundingBox(-400.0, -400.0, -400.0, 400.0, 400.0, 400.0);
  ours.setOccupiedVoxelsAtPointsFromCloud(cloud);
  ASSERT_GE(ours.getTreeDepth(), 14u);
  double lo[3], hi[3];  // padded to 2^depth voxels a side
  ours.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  pcl::octree::OctreePointCloudSearch<PointXYZ> ref(res);
  ref.defineBoundingBox(-400.0, -400.0, -400.0, 400.0, 400.0, 400.0);
  ref.setInputCloud(cloud);
  ref.addPointsFromInputCloud();

  std::uniform_real_distribution<float> far(-390.0f, 390.0f);
  std::uniform_int_distribution<std::size_t> pick(0, cloud->size() - 1);
  std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> rays;  // origin, direction
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector3f origin(far(rng), far(rng), far(rng));
    rays.emplace_back(origin, (*cloud)[pick(rng)].getVector3fMap() - origin);
  }
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3f p = (*cloud)[cloud->size() - 1 - 9 * i].getVector3fMap();
    rays.emplace_back(Eigen::Vector3f(-390.0f, p.y(), p.z()), Eigen::Vector3f(1, 0, 0));  // along an axis
    rays.emplace_back(p, Eigen::Vector3f(1, 1, 0));                                       // diagonals
    rays.emplace_back(p - Eigen::Vector3f(300, 300, 300), Eigen::Vector3f(1, 1, 1));
    rays.emplace_back(Eigen::Vector3f(-1000.0f, p.y() + 0.3f, p.z()), p - Eigen::Vector3f(-1000, 0, 0));
  }
  std::size_t hits = 0;
  for (const auto& [origin, direction] : rays) {
    Ours::AlignedPointTVector centres;
    pcl::octree::OctreePointCloudSearch<PointXYZ>::AlignedPointTVector pcl_centres;
    ours.getIntersectedVoxelCenters(origin, direction, centres, 0);
    ref.getIntersectedVoxelCenters(origin, direction, pcl_centres, 0);
    std::vector<std::array<long, 3>> ours_cells;
    for (const PointXYZ& c : centres)
      ours_cells.push_back({long(std::floor((c.x - lo[0]) / res)), long(std::floor((c.y - lo[1]) / res)),
                            long(std::floor((c.z - lo[2]) / res))});
    ASSERT_EQ(ours_cells, voxelsStepByStep(ours, origin, direction))
        << "ray from (" << origin.transpose() << ") along (" << direction.transpose() << ")";
    expectSameRayAnswer(origin, direction, lo, res, pcl_centres, centres);
    hits += centres.size();
  }
  EXPECT_GT(hits, rays.size() / 2) << "rays aimed at the cloud hit it";

  // At a power-of-two resolution, rays from voxel corners with small integer slopes cross faces of several
  // axes at one distance, exactly: a jump must break those ties as the steps do.
  Ours exact(0.0625);
  exact.defineBoundingBox(-512.0, -512.0, -512.0, 512.0, 512.0, 512.0);
  exact.setOccupiedVoxelsAtPointsFromCloud(cloud);
  const std::array<float, 3> slopes[] = {{1, 1, 1}, {1, 2, 0}, {2, 1, 0}, {1, 2, 2}, {-2, 1, 1}, {1, -1, 2}};
  for (int i = 0; i < 6; ++i)
    for (const auto& s : slopes) {
      const Eigen::Vector3f d(s[0], s[1], s[2]);
      const Eigen::Vector3f origin =
          Eigen::Vector3f(0.0625f * float(5 * i), 0.25f * float(i), 1.0f) - 100.0f * d;
      Ours::AlignedPointTVector centres;
      exact.getIntersectedVoxelCenters(origin, d, centres, 0);
      std::vector<std::array<long, 3>> cells;
      for (const PointXYZ& c : centres)
        cells.push_back({long(std::floor((c.x + 512.0) / 0.0625)), long(std::floor((c.y + 512.0) / 0.0625)),
                         long(std::floor((c.z + 512.0) / 0.0625))});
      ASSERT_EQ(cells, voxelsStepByStep(exact, origin, d))
          << "ray from (" << origin.transpose() << ") along (" << d.transpose() << ")";
    }
}
