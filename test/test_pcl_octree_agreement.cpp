// The occupied voxel set of a FastOctTree equals pcl::octree's on the scans.
#include <gtest/gtest.h>

#include <pcl/common/point_tests.h>  // PCL 1.13's occupancy header uses isFinite without including it
#include <pcl/octree/octree_pointcloud_occupancy.h>

#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/tree/fast_oct_tree.h>

#include "scan_data.h"

using namespace pcl::fot;

namespace {

struct Case {
  std::string scan;
  double resolution;
  pcl_fot_test::ScanSet set;
};

void PrintTo(const Case& c, std::ostream* os) {
  *os << c.scan << " at " << c.resolution << " m";
}

class PclOccupancyAgreement : public ::testing::TestWithParam<Case> {
  void SetUp() override {
    if (!pcl_fot_test::useScans(GetParam().set)) GTEST_SKIP() << pcl_fot_test::missingScansMessage();
  }
};

}  // namespace

TEST_P(PclOccupancyAgreement, SameOccupiedVoxels) {
  const auto cloud = pcl_fot_test::loadScan(GetParam().scan);
  const double res = GetParam().resolution;

  pcl::octree::OctreePointCloudOccupancy<pcl::PointXYZ> reference(res);
  reference.setInputCloud(cloud);
  reference.defineBoundingBox();
  reference.setOccupiedVoxelsAtPointsFromCloud(cloud);
  double min_x, min_y, min_z, max_x, max_y, max_z;
  reference.getBoundingBox(min_x, min_y, min_z, max_x, max_y, max_z);

  // Same origin: the voxel grids coincide.
  FastOctTree tree(res, min_x, min_y, min_z);
  const InsertStats stats = insertPointCloud(tree, *cloud);
  std::size_t finite = 0;
  for (const auto& p : *cloud) finite += pcl::isFinite(p);
  EXPECT_EQ(stats.inserted, finite);
  EXPECT_EQ(stats.non_finite, cloud->size() - finite);

  // Keys, not centres: float centres lose the cell at UTM-sized coordinates.
  ASSERT_EQ(tree.getOccupiedCount(), reference.getLeafCount());
  std::size_t leaves = 0;
  for (auto it = reference.leaf_depth_begin(); it != reference.leaf_depth_end(); ++it, ++leaves) {
    const pcl::octree::OctreeKey& k = it.getCurrentOctreeKey();
    const Key key{std::int32_t(k.x), std::int32_t(k.y), std::int32_t(k.z)};
    ASSERT_EQ(tree.getCell(key), CellState::Occupied) << "pcl::octree voxel " << toString(key);
  }
  EXPECT_EQ(leaves, reference.getLeafCount());
}

std::vector<Case> allCases(pcl_fot_test::ScanSet set) {
  std::vector<Case> cases;
  for (const auto& scan : pcl_fot_test::allScans())
    for (double res : {0.01, 0.05}) cases.push_back({scan, res, set});
  return cases;
}

std::string caseName(const ::testing::TestParamInfo<Case>& info) {
  std::string name = info.param.scan.substr(0, info.param.scan.find('.'));
  return name + (info.param.resolution == 0.01 ? "_1cm" : "_5cm");
}

INSTANTIATE_TEST_SUITE_P(Synthetic, PclOccupancyAgreement,
                         ::testing::ValuesIn(allCases(pcl_fot_test::ScanSet::Synthetic)), caseName);
INSTANTIATE_TEST_SUITE_P(Real, PclOccupancyAgreement,
                         ::testing::ValuesIn(allCases(pcl_fot_test::ScanSet::Real)), caseName);
