// Exports for pcl_viewer, read back through PCL's own readers.
#include <gtest/gtest.h>

#include <cstdio>
#include <set>
#include <tuple>

#include <pcl/PolygonMesh.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/vtk_lib_io.h>
#include <unistd.h>

#include <pcl_fot/io/voxel_export.h>
#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/tree/accessor.h>

#include "scan_data.h"

using namespace pcl::fot;

namespace {

const FastOctTree& roomMap() {
  return pcl_fot_test::perScanSet<FastOctTree>([] {
    FastOctTree t(0.1, 0.05, 0.0, -0.05);
    insertScan(t, *pcl_fot_test::loadScan("room_scan1.pcd"));
    return t;
  });
}

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "pcl_fot_" + std::to_string(::getpid()) + "_" + name;
}

using Centre = std::tuple<float, float, float>;

std::set<Centre> centres(const FastOctTree& t, CellState s) {
  std::set<Centre> out;
  t.forEachCell(s, [&](const Key& k) {
    double x, y, z;
    t.getGrid().keyToCenter(k, x, y, z);
    out.insert({float(x), float(y), float(z)});
  });
  return out;
}

}  // namespace

PCL_FOT_SCAN_TESTS(VoxelExport);

TEST_P(VoxelExport, PcdHoldsTheCellCentresWithAnIdentityViewpoint) {
  const FastOctTree& map = roomMap();
  const std::string path = tempPath("centres.pcd");
  EXPECT_EQ(io::saveVoxelCentersPCD(map, path), map.getOccupiedCount());
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(path, cloud), 0);
  std::set<Centre> read;
  for (const auto& p : cloud) read.insert({p.x, p.y, p.z});
  EXPECT_EQ(read, centres(map, CellState::Occupied));
  EXPECT_TRUE(cloud.sensor_origin_.isZero());
  EXPECT_TRUE(cloud.sensor_orientation_.coeffs().isApprox(Eigen::Quaternionf::Identity().coeffs()));
  std::set<std::uint32_t> colours;
  for (const auto& p : cloud) colours.insert(p.rgba & 0xFFFFFFu);
  EXPECT_GT(colours.size(), 10u) << "coloured by height";

  io::VoxelExportOptions both;
  both.include_free = true;
  both.coloring = io::VoxelColoring::State;
  EXPECT_EQ(io::saveVoxelCentersPCD(map, path, both), map.getOccupiedCount() + map.getFreeCount());
  ASSERT_EQ(pcl::io::loadPCDFile(path, cloud), 0);
  colours.clear();
  for (const auto& p : cloud) colours.insert(p.rgba & 0xFFFFFFu);
  EXPECT_EQ(colours.size(), 2u) << "one colour per state";
  std::remove(path.c_str());
}

TEST_P(VoxelExport, VtkMeshHasOneQuadPerExposedFace) {
  const FastOctTree& map = roomMap();
  // The faces an occupied voxel shares with a voxel that is not occupied, counted cell by cell.
  std::size_t exposed = 0;
  ConstAccessor cells(map);
  map.forEachCell(CellState::Occupied, [&](const Key& k) {
    for (const Key& n : {Key{k.x - 1, k.y, k.z}, Key{k.x + 1, k.y, k.z}, Key{k.x, k.y - 1, k.z},
                         Key{k.x, k.y + 1, k.z}, Key{k.x, k.y, k.z - 1}, Key{k.x, k.y, k.z + 1}})
      exposed += cells.getCell(n) != CellState::Occupied;
  });
  const std::string path = tempPath("mesh.vtk");
  EXPECT_EQ(io::saveVoxelMeshVTK(map, path), exposed);
  pcl::PolygonMesh mesh;
  ASSERT_GT(pcl::io::loadPolygonFileVTK(path, mesh), 0);
  ASSERT_EQ(mesh.polygons.size(), exposed);
  for (const auto& polygon : mesh.polygons) ASSERT_EQ(polygon.vertices.size(), 4u);
  pcl::PointCloud<pcl::PointXYZRGB> corners;
  pcl::fromPCLPointCloud2(mesh.cloud, corners);
  EXPECT_EQ(corners.size(), 4 * exposed);
  // Every corner lies on the grid's cell boundaries.
  const double res = map.getResolution();
  for (std::size_t i = 0; i < corners.size(); i += 97) {
    const double fx = (corners[i].x - 0.05) / res, fz = (corners[i].z + 0.05) / res;
    EXPECT_NEAR(fx, std::round(fx), 1e-3);
    EXPECT_NEAR(fz, std::round(fz), 1e-3);
  }
  std::remove(path.c_str());
}

TEST_P(VoxelExport, RefusesTooManyCellsAndUnwritablePaths) {
  const FastOctTree& map = roomMap();
  io::VoxelExportOptions small;
  small.max_cells = 10;
  const std::string path = tempPath("refused.pcd");
  EXPECT_THROW(io::saveVoxelCentersPCD(map, path, small), std::length_error);
  EXPECT_THROW(io::saveVoxelMeshVTK(map, path, small), std::length_error);
  EXPECT_NE(::access(path.c_str(), F_OK), 0) << "nothing written";
  EXPECT_THROW(io::saveVoxelCentersPCD(map, "/nonexistent-dir/x.pcd"), std::runtime_error);
}
