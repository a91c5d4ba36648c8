// OctoMap .bt interoperability, checked through the OctoMap library itself.
#include <gtest/gtest.h>

#include <random>
#include <sstream>

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>

#include <pcl_fot/io/octomap.h>
#include <pcl_fot/pcl/cloud_insertion.h>

#include "octomap_checks.h"
#include "scan_data.h"

using namespace pcl::fot;

namespace {

const pcl::PointCloud<pcl::PointXYZ>& roomScan() {
  return *pcl_fot_test::perScanSet<pcl::PointCloud<pcl::PointXYZ>::Ptr>(
      [] { return pcl_fot_test::loadScan("room_scan1.pcd"); });
}

/** room_scan1 ray-traced at 5 cm on the given grid. */
FastOctTree ourMap(const CellGrid& grid) {
  FastOctTree t(grid);
  insertScan(t, roomScan());
  return t;
}

std::unique_ptr<octomap::OcTree> readWithOctoMap(const std::string& bt) {
  std::istringstream in(bt);
  auto tree = std::make_unique<octomap::OcTree>(0.1);
  EXPECT_TRUE(tree->readBinary(in)) << "OctoMap refuses the file";
  return tree;
}

}  // namespace

PCL_FOT_SCAN_TESTS(OctoMapBtOnScans);

TEST_P(OctoMapBtOnScans, ExportedMapsLoadInOctoMapWithOurCells) {
  for (const CellGrid& grid : {CellGrid(0.05), CellGrid(0.05, 0.15, -0.1, 2.0)}) {
    const FastOctTree ours = ourMap(grid);
    ASSERT_GT(ours.getFreeCount(), 100000u);
    const auto om = readWithOctoMap(io::encodeBt(ours));
    EXPECT_EQ(om->getResolution(), 0.05);
    expectSameCells(*om, ours);
  }
}

TEST_P(OctoMapBtOnScans, ImportedOctoMapsHaveOctoMapsCells) {
  octomap::OcTree om(0.05);
  octomap::Pointcloud scan;
  for (const auto& p : roomScan()) scan.push_back(p.x, p.y, p.z);
  om.insertPointCloud(scan, octomap::point3d(0, 0, 0));
  om.toMaxLikelihood();
  om.prune();
  std::ostringstream out;
  ASSERT_TRUE(om.writeBinaryConst(out));
  const std::string bt = out.str();
  const FastOctTree ours = io::decodeBt(bt.data(), bt.size(), "octomap.bt");
  expectSameCells(om, ours);
  // The same cells on a grid whose origin is a whole number of cells away.
  io::OctoMapImportOptions shifted;
  shifted.origin[0] = -0.25;
  shifted.origin[2] = 0.1;
  expectSameCells(om, io::decodeBt(bt.data(), bt.size(), "octomap.bt", shifted));
  // And back again, through our writer and OctoMap's reader.
  expectSameCells(*readWithOctoMap(io::encodeBt(ours)), ours);
}

TEST(OctoMapBt, PrunedCubesFarFromTheOriginImport) {
  // A cube of free space 11 m out: OctoMap prunes most of it into inner nodes, which the importer sets as
  // boxes on a fresh tree. That used to fail with MemoryLimitError.
  octomap::OcTree om(0.1);
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 8; ++k)
        om.updateNode(octomap::point3d(11.25f + 0.1f * i, 11.25f + 0.1f * j, 11.25f + 0.1f * k), false);
  om.updateInnerOccupancy();
  om.prune();
  ASSERT_LT(om.getNumLeafNodes(), 512u) << "the cube should have pruned inner nodes";
  std::ostringstream out;
  ASSERT_TRUE(om.writeBinaryConst(out));
  const std::string bt = out.str();
  expectSameCells(om, io::decodeBt(bt.data(), bt.size(), "cube.bt"));
}

TEST_P(OctoMapBtOnScans, EveryOccupancyTreeTypeImports) {
  // ColorOcTree and OcTreeStamped write the same .bt body under their own id; OctoMap reads them as OcTrees.
  auto check = [](auto& om) {
    octomap::Pointcloud scan;
    for (const auto& p : roomScan()) scan.push_back(p.x, p.y, p.z);
    om.insertPointCloud(scan, octomap::point3d(0, 0, 0));
    std::ostringstream out;
    ASSERT_TRUE(om.writeBinary(out));  // maximum likelihood, then pruned
    const std::string bt = out.str();
    ASSERT_NE(bt.find("id " + om.getTreeType()), std::string::npos);
    expectSameCells(om, io::decodeBt(bt.data(), bt.size(), "typed.bt"));
  };
  octomap::ColorOcTree color(0.1);
  check(color);
  octomap::OcTreeStamped stamped(0.1);
  check(stamped);
}

TEST_P(OctoMapBtOnScans, RoundTripAndEmptyMaps) {
  const FastOctTree ours = ourMap(CellGrid(0.05));
  const std::string bt = io::encodeBt(ours);
  EXPECT_TRUE(io::decodeBt(bt.data(), bt.size()) == ours);
  const FastOctTree empty(0.1);
  const std::string e = io::encodeBt(empty);
  EXPECT_EQ(readWithOctoMap(e)->size(), 0u);
  EXPECT_TRUE(io::decodeBt(e.data(), e.size()).empty());
}

TEST_P(OctoMapBtOnScans, WhatOctoMapCannotHoldIsRefused) {
  FastOctTree off(0.05, 0.01, 0.0, 0.0);  // boundaries off OctoMap's grid
  off.setCell({1, 2, 3}, CellState::Occupied);
  EXPECT_THROW(io::encodeBt(off), std::invalid_argument);
  FastOctTree far(0.05);
  far.setCell({40000, 0, 0}, CellState::Occupied);  // beyond 32768 cells from 0
  EXPECT_THROW(io::encodeBt(far), std::invalid_argument);
  const std::string bt = io::encodeBt(ourMap(CellGrid(0.05)));
  io::OctoMapImportOptions off_grid;
  off_grid.origin[1] = 0.02;
  EXPECT_THROW(io::decodeBt(bt.data(), bt.size(), "x.bt", off_grid), std::invalid_argument);
}

TEST_P(OctoMapBtOnScans, DamagedFilesFailCleanlyOrLoadValidMaps) {
  const std::string good = io::encodeBt(ourMap(CellGrid(0.2)));  // coarse, so that 1000 variants stay quick
  const std::size_t body = good.find("data\n") + 5;
  io::OctoMapImportOptions capped;
  capped.max_pool_bytes = 8 << 20;  // a flipped bit can turn an inner node into a huge leaf
  std::mt19937 rng(1);
  int refused = 0, loaded = 0;
  auto attempt = [&](const std::string& bytes) {
    (loadsAValidMap(
         [&](const std::string& b) { return io::decodeBt(b.data(), b.size(), "damaged.bt", capped); }, bytes)
         ? loaded
         : refused)++;
  };
  for (int i = 0; i < 400; ++i) attempt(good.substr(0, rng() % good.size()));
  for (int i = 0; i < 500; ++i) {
    std::string b = good;
    b[body + rng() % (b.size() - body)] ^= char(1u << (rng() % 8));
    attempt(b);
  }
  for (int i = 0; i < 100; ++i) {
    std::string b = good;
    b[rng() % body] ^= char(1u << (rng() % 8));
    attempt(b);
  }
  EXPECT_EQ(refused + loaded, 1000);
  EXPECT_GT(refused, 400);
}
