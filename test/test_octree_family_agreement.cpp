// The pcl::octree look-alikes with leaves (point vectors, single points, densities, centroids, change
// detection, adjacency) give pcl::octree's answers, call for call, on real scans and crowded clouds.
#include <gtest/gtest.h>

#include <array>
#include <map>
#include <random>
#include <string>

#include <pcl/common/point_tests.h>
#include <pcl/octree/octree_pointcloud_adjacency.h>
#include <pcl/octree/octree_pointcloud_changedetector.h>
#include <pcl/octree/octree_pointcloud_density.h>
#include <pcl/octree/octree_pointcloud_pointvector.h>
#include <pcl/octree/octree_pointcloud_singlepoint.h>
#include <pcl/octree/octree_pointcloud_voxelcentroid.h>

#include <pcl_fot/pcl/octree/octree.h>

#include "scan_data.h"

using pcl::Indices;
using pcl::PointXYZ;
using Cloud = pcl::PointCloud<PointXYZ>;

namespace {

/** The leaves of both octrees, depth first: the same keys, depths and containers' points. */
template <typename Reference, typename Ours>
void expectSameLeaves(Reference& ref, Ours& ours) {
  ASSERT_EQ(ref.getLeafCount(), ours.getLeafCount());
  ASSERT_EQ(ref.getBranchCount(), ours.getBranchCount());
  auto r = ref.leaf_depth_begin();
  auto o = ours.leaf_depth_begin();
  for (std::size_t n = 0; r != ref.leaf_depth_end(); ++r, ++o, ++n) {
    ASSERT_TRUE(o != ours.leaf_depth_end()) << "ours ends after " << n << " leaves";
    ASSERT_EQ(r.getCurrentOctreeKey(), o.getCurrentOctreeKey()) << "leaf " << n;
    ASSERT_EQ(r.getCurrentOctreeDepth(), o.getCurrentOctreeDepth()) << "leaf " << n;
    ASSERT_EQ(o.getCurrentOctreeNode()->getNodeType(), pcl::octree::LEAF_NODE);
    Indices ri, oi;
    r.getLeafContainer().getPointIndices(ri);
    o.getLeafContainer().getPointIndices(oi);
    ASSERT_EQ(ri, oi) << "leaf " << n;
    ASSERT_EQ(r.getLeafContainer().getSize(), o.getLeafContainer().getSize());
  }
  EXPECT_TRUE(o == ours.leaf_depth_end());
}

/** Every node of both octrees, depth first: the same keys, depths and kinds. */
template <typename Reference, typename Ours>
void expectSameNodes(Reference& ref, Ours& ours) {
  auto r = ref.depth_begin();
  auto o = ours.depth_begin();
  for (std::size_t n = 0; r != ref.depth_end(); ++r, ++o, ++n) {
    ASSERT_TRUE(o != ours.depth_end()) << "ours ends after " << n << " nodes";
    ASSERT_EQ(r.getCurrentOctreeKey(), o.getCurrentOctreeKey()) << "node " << n;
    ASSERT_EQ(r.getCurrentOctreeDepth(), o.getCurrentOctreeDepth()) << "node " << n;
    ASSERT_EQ(r.isLeafNode(), o.isLeafNode()) << "node " << n;
  }
  EXPECT_TRUE(o == ours.depth_end());
}

/** Every point four times over, in a few voxels: crowded leaves, duplicates. */
Cloud::Ptr crowdedCloud() {
  Cloud::Ptr cloud(new Cloud);
  for (int copy = 0; copy < 4; ++copy)
    for (int i = 0; i < 500; ++i) cloud->emplace_back(0.002f * (i % 10), 0.003f * (i % 7), 0.001f * (i % 13));
  return cloud;
}

bool insideBox(const pcl::octree::OctreePointCloud<PointXYZ>& t, const PointXYZ& p) {
  double lo[3], hi[3];
  t.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  return p.x >= lo[0] && p.y >= lo[1] && p.z >= lo[2] && p.x < hi[0] && p.y < hi[1] && p.z < hi[2];
}

}  // namespace

PCL_FOT_SCAN_TESTS(OctreeFamilyAgreement);

TEST_P(OctreeFamilyAgreement, PointVectorLeavesOnScansAndCrowds) {
  for (const auto& [cloud, res] :
       {std::make_pair(pcl_fot_test::loadScan("kinect_capture0002.pcd"), 0.02),
        std::make_pair(pcl_fot_test::loadScan("room_scan2.pcd"), 0.05), std::make_pair(crowdedCloud(), 0.004),
        std::make_pair(pcl_fot_test::randomCloud(3000, 5, 1), 0.1)})
    for (const std::size_t max_per_leaf : {0, 3, 16}) {
      SCOPED_TRACE(::testing::Message()
                   << cloud->size() << " points at " << res << " m, dynamic depth " << max_per_leaf);
      pcl::octree::OctreePointCloudPointVector<PointXYZ> ref(res);
      pcl::fot::OctreePointCloudPointVector<PointXYZ> ours(res);
      pcl_fot_test::fillBoth(ref, ours, cloud, max_per_leaf);
      expectSameLeaves(ref, ours);
      // The breadth-first walks visit the same nodes in the same order (leaves of several depths included).
      auto rb = ref.leaf_breadth_begin();
      auto ob = ours.leaf_breadth_begin();
      for (; rb != ref.leaf_breadth_end(); ++rb, ++ob) {
        ASSERT_TRUE(ob != ours.leaf_breadth_end());
        ASSERT_EQ(rb.getCurrentOctreeKey(), ob.getCurrentOctreeKey());
        ASSERT_EQ(rb.getCurrentOctreeDepth(), ob.getCurrentOctreeDepth());
      }
      EXPECT_TRUE(ob == ours.leaf_breadth_end());
      auto rn = ref.breadth_begin();
      auto on = ours.breadth_begin();
      for (; rn != ref.breadth_end(); ++rn, ++on) {
        ASSERT_TRUE(on != ours.breadth_end());
        ASSERT_EQ(rn.getCurrentOctreeKey(), on.getCurrentOctreeKey());
        ASSERT_EQ(rn.isLeafNode(), on.isLeafNode());
        ASSERT_EQ(rn.getNodeConfiguration(), on.getNodeConfiguration());
      }
      EXPECT_TRUE(on == ours.breadth_end());
      // Deleting voxels prunes the same way.
      for (std::size_t i = 0; i < cloud->size(); i += 7) {
        if (pcl::isFinite((*cloud)[i]) && insideBox(ref, (*cloud)[i])) {
          ref.deleteVoxelAtPoint((*cloud)[i]);
          ours.deleteVoxelAtPoint((*cloud)[i]);
        }
      }
      expectSameLeaves(ref, ours);
    }
}

TEST_P(OctreeFamilyAgreement, SinglePointKeepsTheLastIndex) {
  const auto cloud = pcl_fot_test::loadScan("room_scan1.pcd");
  pcl::octree::OctreePointCloudSinglePoint<PointXYZ> ref(0.05);
  pcl::fot::OctreePointCloudSinglePoint<PointXYZ> ours(0.05);
  pcl_fot_test::fillBoth(ref, ours, cloud);
  expectSameLeaves(ref, ours);
}

TEST_P(OctreeFamilyAgreement, DensityCountsEveryPoint) {
  for (const auto& [cloud, res] : {std::make_pair(pcl_fot_test::loadScan("kinect_capture0003.pcd"), 0.05),
                                   std::make_pair(crowdedCloud(), 0.004)}) {
    pcl::octree::OctreePointCloudDensity<PointXYZ> ref(res);
    pcl::fot::OctreePointCloudDensity<PointXYZ> ours(res);
    pcl_fot_test::fillBoth(ref, ours, cloud);
    ASSERT_EQ(ref.getLeafCount(), ours.getLeafCount());
    std::size_t total = 0;
    for (auto it = ours.leaf_depth_begin(); it != ours.leaf_depth_end(); ++it)
      total += it.getLeafContainer().getPointCounter();
    std::size_t finite = 0;
    for (const auto& p : *cloud) finite += pcl::isFinite(p);
    EXPECT_EQ(total, finite);
    for (std::size_t i = 0; i < cloud->size(); i += 13) {
      const PointXYZ& p = (*cloud)[i];
      if (pcl::isFinite(p)) {
        ASSERT_EQ(ref.getVoxelDensityAtPoint(p), ours.getVoxelDensityAtPoint(p)) << i;
      }
    }
    EXPECT_EQ(ours.getVoxelDensityAtPoint(PointXYZ(1e4f, 0, 0)), 0u) << "outside the box";
  }
}

TEST_P(OctreeFamilyAgreement, VoxelCentroidsBitForBit) {
  for (const auto& [cloud, res] : {std::make_pair(pcl_fot_test::loadScan("room_scan1.pcd"), 0.1),
                                   std::make_pair(pcl_fot_test::loadScan("terrain_samp11.pcd"), 1.0),
                                   std::make_pair(crowdedCloud(), 0.004)}) {
    pcl::octree::OctreePointCloudVoxelCentroid<PointXYZ> ref(res);
    pcl::fot::OctreePointCloudVoxelCentroid<PointXYZ> ours(res);
    pcl_fot_test::fillBoth(ref, ours, cloud);
    pcl::octree::OctreePointCloudVoxelCentroid<PointXYZ>::AlignedPointTVector rc;
    pcl::fot::OctreePointCloudVoxelCentroid<PointXYZ>::AlignedPointTVector oc;
    ASSERT_EQ(ref.getVoxelCentroids(rc), ours.getVoxelCentroids(oc));
    for (std::size_t i = 0; i < rc.size(); ++i) {
      ASSERT_EQ(rc[i].x, oc[i].x) << i;
      ASSERT_EQ(rc[i].y, oc[i].y) << i;
      ASSERT_EQ(rc[i].z, oc[i].z) << i;
    }
    // PCL's getVoxelCentroidAtPoint does not compile (1.13): its leaves' centroids, by key, stand in.
    std::map<std::array<pcl::uindex_t, 3>, PointXYZ> by_key;
    for (auto it = ref.leaf_depth_begin(); it != ref.leaf_depth_end(); ++it) {
      const auto& k = it.getCurrentOctreeKey();
      it.getLeafContainer().getCentroid(by_key[{k.x, k.y, k.z}]);
    }
    double lo[3], hi[3];
    ref.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    for (std::size_t i = 0; i < cloud->size(); i += 101) {
      const PointXYZ& p = (*cloud)[i];
      if (!pcl::isFinite(p)) continue;
      PointXYZ o;
      ASSERT_TRUE(ours.getVoxelCentroidAtPoint(p, o));
      const PointXYZ& r = by_key.at({pcl::uindex_t((p.x - lo[0]) / res), pcl::uindex_t((p.y - lo[1]) / res),
                                     pcl::uindex_t((p.z - lo[2]) / res)});
      ASSERT_EQ(r.x, o.x);
      ASSERT_EQ(r.y, o.y);
      ASSERT_EQ(r.z, o.z);
    }
  }
}

TEST_P(OctreeFamilyAgreement, ChangeDetectorFindsTheSameNewPoints) {
  // Two Kinect frames of one scene, and two room scans: the second cloud against the first.
  for (const auto& [a, b, res] :
       {std::make_tuple(std::string("kinect_capture0001.pcd"), std::string("kinect_capture0002.pcd"), 0.02),
        std::make_tuple(std::string("room_scan1.pcd"), std::string("room_scan2.pcd"), 0.1)}) {
    const auto first = pcl_fot_test::loadScan(a), second = pcl_fot_test::loadScan(b);
    pcl::octree::OctreePointCloudChangeDetector<PointXYZ> ref(res);
    pcl::fot::OctreePointCloudChangeDetector<PointXYZ> ours(res);
    pcl_fot_test::fillBoth(ref, ours, first);
    ref.switchBuffers();
    ours.switchBuffers();
    EXPECT_EQ(ours.getLeafCount(), 0u);
    pcl_fot_test::fillBoth(ref, ours, second);
    // PCL's iterators do not walk a double-buffered octree reliably (they can loop forever): no leaf walk.
    ASSERT_EQ(ref.getLeafCount(), ours.getLeafCount());
    for (const pcl::uindex_t min_points : {0u, 1u, 4u}) {
      Indices ri, oi;
      ASSERT_EQ(ref.getPointIndicesFromNewVoxels(ri, min_points),
                ours.getPointIndicesFromNewVoxels(oi, min_points));
      ASSERT_EQ(ri, oi) << a << " then " << b << ", at least " << min_points << " points";
      EXPECT_FALSE(oi.empty());
    }
  }
}

TEST_P(OctreeFamilyAgreement, AdjacencyLinksTheSameNeighbours) {
  for (const auto& [cloud, res] : {std::make_pair(pcl_fot_test::loadScan("room_scan1.pcd"), 0.05),
                                   std::make_pair(pcl_fot_test::loadScan("kinect_capture0001.pcd"), 0.01)}) {
    pcl::octree::OctreePointCloudAdjacency<PointXYZ> ref(res);
    pcl::fot::OctreePointCloudAdjacency<PointXYZ> ours(res);
    ref.setInputCloud(cloud);
    ours.setInputCloud(cloud);
    ref.addPointsFromInputCloud();
    ours.addPointsFromInputCloud();
    ASSERT_EQ(ref.size(), ours.size());
    // The same leaves in order, each linked to the same neighbours in the same order (as leaf numbers).
    std::map<const void*, std::size_t> ref_number, our_number;
    auto r = ref.leaf_depth_begin();
    auto o = ours.leaf_depth_begin();
    for (; r != ref.leaf_depth_end(); ++r, ++o) {
      ASSERT_EQ(r.getCurrentOctreeKey(), o.getCurrentOctreeKey());
      ASSERT_EQ(r.getLeafContainer().size(), o.getLeafContainer().size());
      ASSERT_EQ(r.getLeafContainer().getPointCounter(), o.getLeafContainer().getPointCounter());
      ref_number.emplace(&r.getLeafContainer(), ref_number.size());
      our_number.emplace(&o.getLeafContainer(), our_number.size());
    }
    for (r = ref.leaf_depth_begin(), o = ours.leaf_depth_begin(); r != ref.leaf_depth_end(); ++r, ++o) {
      std::vector<std::size_t> ref_links, our_links;
      for (auto n = r.getLeafContainer().cbegin(); n != r.getLeafContainer().cend(); ++n)
        ref_links.push_back(ref_number.at(*n));
      for (auto n = o.getLeafContainer().cbegin(); n != o.getLeafContainer().cend(); ++n)
        our_links.push_back(our_number.at(*n));
      ASSERT_EQ(ref_links, our_links);
    }
    // PCL's occlusion walk reads keys outside the box as if they were inside: compare with the camera inside.
    const PointXYZ camera(0, 0, 0);
    double lo[3], hi[3];
    ours.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    const bool camera_inside = lo[0] < 0 && lo[1] < 0 && lo[2] < 0 && hi[0] > 0 && hi[1] > 0 && hi[2] > 0;
    std::size_t occluded = 0;
    for (std::size_t i = 0; i < cloud->size(); i += 97) {
      const PointXYZ& p = (*cloud)[i];
      if (!pcl::isFinite(p)) continue;
      ASSERT_EQ(ref.getLeafContainerAtPoint(p)->size(), ours.getLeafContainerAtPoint(p)->size());
      if (camera_inside) {
        ASSERT_EQ(ref.testForOcclusion(p, camera), ours.testForOcclusion(p, camera)) << i;
        occluded += ours.testForOcclusion(p, camera);
      }
    }
    if (camera_inside) {
      EXPECT_GT(occluded, 0u);
    }
    pcl::octree::OctreePointCloudAdjacency<PointXYZ>::VoxelAdjacencyList rg;
    pcl::fot::OctreePointCloudAdjacency<PointXYZ>::VoxelAdjacencyList og;
    ref.computeVoxelAdjacencyGraph(rg);
    ours.computeVoxelAdjacencyGraph(og);
    EXPECT_EQ(boost::num_vertices(rg), boost::num_vertices(og));
    EXPECT_EQ(boost::num_edges(rg), boost::num_edges(og));
  }
}

namespace {

/** A user's octree that adds points its own way: it must see every point addPointsFromInputCloud adds. */
class CountingPointVector : public pcl::fot::OctreePointCloudPointVector<PointXYZ> {
 public:
  using pcl::fot::OctreePointCloudPointVector<PointXYZ>::OctreePointCloudPointVector;
  std::size_t added = 0;

 protected:
  void addPointIdx(pcl::uindex_t point_idx_arg) override {
    ++added;
    pcl::fot::OctreePointCloudPointVector<PointXYZ>::addPointIdx(point_idx_arg);
  }
};

}  // namespace

TEST(OctreeFamilyAgreement, ACloudAddedAtOnceGrowsAndFillsAsPointByPoint) {
  // The first point alone, then points that grow the box down and up, duplicates, NaNs, and a second call
  // through indices (repeats included) into the filled octree: addPointsFromInputCloud sorts the points
  // into their leaves, and must leave what PCL's point-by-point insertion leaves.
  Cloud::Ptr cloud(new Cloud);
  std::mt19937 rng(46);
  std::uniform_real_distribution<float> near(-0.3f, 0.3f);
  cloud->emplace_back(0.01f, 0.02f, 0.03f);
  for (int i = 0; i < 3000; ++i) {
    const float far = i % 500 == 0 ? -40.0f + 0.03f * i : 1.0f;
    cloud->emplace_back(near(rng) * far, near(rng), near(rng) * (i % 3 == 0 ? 9.0f : 1.0f));
    if (i % 97 == 0) cloud->push_back(cloud->back());
    if (i % 211 == 0) cloud->emplace_back(NAN, 0.0f, 0.0f);
  }
  pcl::octree::OctreePointCloudPointVector<PointXYZ> ref(0.02);
  pcl::fot::OctreePointCloudPointVector<PointXYZ> ours(0.02);
  CountingPointVector counting(0.02);
  pcl_fot_test::fillBoth(ref, ours, cloud);
  counting.setInputCloud(cloud);
  counting.addPointsFromInputCloud();
  expectSameLeaves(ref, ours);
  expectSameLeaves(ref, counting);
  expectSameNodes(ref, ours);
  std::size_t finite = 0;
  for (const auto& p : *cloud) finite += pcl::isFinite(p);
  EXPECT_EQ(counting.added, finite);

  pcl::IndicesPtr indices(new Indices);
  for (int i = 0; i < 2000; i += 3) indices->push_back((i * 7919) % static_cast<int>(cloud->size()));
  indices->push_back(indices->front());
  for (auto* octree : {static_cast<pcl::fot::OctreePointCloudPointVector<PointXYZ>*>(&ours),
                       static_cast<pcl::fot::OctreePointCloudPointVector<PointXYZ>*>(&counting)})
    octree->setInputCloud(cloud, indices);
  ref.setInputCloud(cloud, indices);
  ref.addPointsFromInputCloud();
  ours.addPointsFromInputCloud();
  counting.addPointsFromInputCloud();
  expectSameLeaves(ref, ours);
  expectSameLeaves(ref, counting);
  expectSameNodes(ref, ours);
}
