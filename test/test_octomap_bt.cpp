// OctoMap .bt interoperability, checked through the OctoMap library itself.
#include <gtest/gtest.h>

#include <random>
#include <sstream>

#include <octomap/OcTree.h>

#include <pcl_fot/io/octomap_bt.h>
#include <pcl_fot/occupancy_mapping.h>

#include "scan_data.h"

using namespace pcl::fot;

namespace {

const pcl::PointCloud<pcl::PointXYZ>& roomScan() {
  static const auto cloud = pcl_fot_test::loadScan("room_scan1.pcd");
  return *cloud;
}

/** room_scan1 ray-traced at 5 cm on the given grid. */
FastOctTree ourMap(const VoxelGrid& grid) {
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

/**
 * Expects `ours` to hold exactly OctoMap's free and occupied cells: every OctoMap leaf is a box of one
 * state in ours, and the cell counts agree, so nothing else is known in ours either.
 */
void expectSameCells(const octomap::OcTree& om, const FastOctTree& ours) {
  const double res = om.getResolution();
  ASSERT_DOUBLE_EQ(ours.getResolution(), res);
  std::uint64_t occupied = 0, free = 0;
  for (auto it = om.begin_leafs(); it != om.end_leafs(); ++it) {
    const std::uint64_t side = std::uint64_t(1) << (16 - it.getDepth());
    const octomap::OcTreeKey k = it.getIndexKey();
    const CellState want = om.isNodeOccupied(*it) ? CellState::Occupied : CellState::Free;
    (want == CellState::Occupied ? occupied : free) += side * side * side;
    // OctoMap key K is cell floor(c / res) + 32768; ours is floor((c - origin) / res).
    Key lo;
    for (int a = 0; a < 3; ++a)
      (&lo.x)[a] = std::int32_t(k[a]) - 32768 - std::int32_t(std::lround(ours.getGrid().origin()[a] / res));
    const Key hi{lo.x + std::int32_t(side) - 1, lo.y + std::int32_t(side) - 1, lo.z + std::int32_t(side) - 1};
    std::uint64_t covered = 0;
    bool same = true;
    ours.forEachRegionInBox(lo, hi, [&](const Region& r) {
      same = same && r.state == want;
      std::uint64_t v = 1;
      const std::int64_t rs = std::int64_t(1) << r.level;
      const std::int64_t rl[3] = {r.min_key.x, r.min_key.y, r.min_key.z}, bl[3] = {lo.x, lo.y, lo.z},
                         bh[3] = {hi.x, hi.y, hi.z};
      for (int a = 0; a < 3; ++a)
        v *= std::uint64_t(std::min(rl[a] + rs - 1, bh[a]) - std::max(rl[a], bl[a]) + 1);
      covered += v;
    });
    ASSERT_TRUE(same && covered == side * side * side)
        << "OctoMap leaf at " << toString(lo) << ", side " << side;
  }
  EXPECT_EQ(ours.getOccupiedCount(), occupied);
  EXPECT_EQ(ours.getFreeCount(), free);
}

}  // namespace

TEST(OctoMapBt, ExportedMapsLoadInOctoMapWithOurCells) {
  for (const VoxelGrid& grid : {VoxelGrid(0.05), VoxelGrid(0.05, 0.15, -0.1, 2.0)}) {
    const FastOctTree ours = ourMap(grid);
    ASSERT_GT(ours.getFreeCount(), 100000u);
    const auto om = readWithOctoMap(io::encodeBt(ours));
    EXPECT_EQ(om->getResolution(), 0.05);
    expectSameCells(*om, ours);
  }
}

TEST(OctoMapBt, ImportedOctoMapsHaveOctoMapsCells) {
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
  io::BtImportOptions shifted;
  shifted.origin[0] = -0.25;
  shifted.origin[2] = 0.1;
  expectSameCells(om, io::decodeBt(bt.data(), bt.size(), "octomap.bt", shifted));
  // And back again, through our writer and OctoMap's reader.
  expectSameCells(*readWithOctoMap(io::encodeBt(ours)), ours);
}

TEST(OctoMapBt, RoundTripAndEmptyMaps) {
  const FastOctTree ours = ourMap(VoxelGrid(0.05));
  const std::string bt = io::encodeBt(ours);
  EXPECT_TRUE(io::decodeBt(bt.data(), bt.size()) == ours);
  const FastOctTree empty(0.1);
  const std::string e = io::encodeBt(empty);
  EXPECT_EQ(readWithOctoMap(e)->size(), 0u);
  EXPECT_TRUE(io::decodeBt(e.data(), e.size()).empty());
}

TEST(OctoMapBt, WhatOctoMapCannotHoldIsRefused) {
  FastOctTree off(0.05, 0.01, 0.0, 0.0);  // boundaries off OctoMap's grid
  off.setCell({1, 2, 3}, CellState::Occupied);
  EXPECT_THROW(io::encodeBt(off), std::invalid_argument);
  FastOctTree far(0.05);
  far.setCell({40000, 0, 0}, CellState::Occupied);  // beyond 32768 cells from 0
  EXPECT_THROW(io::encodeBt(far), std::invalid_argument);
  const std::string bt = io::encodeBt(ourMap(VoxelGrid(0.05)));
  io::BtImportOptions off_grid;
  off_grid.origin[1] = 0.02;
  EXPECT_THROW(io::decodeBt(bt.data(), bt.size(), "x.bt", off_grid), std::invalid_argument);
}

TEST(OctoMapBt, DamagedFilesFailCleanlyOrLoadValidMaps) {
  const std::string good = io::encodeBt(ourMap(VoxelGrid(0.2)));  // coarse, so that 1000 variants stay quick
  const std::size_t body = good.find("data\n") + 5;
  io::BtImportOptions capped;
  capped.max_pool_bytes = 8 << 20;  // a flipped bit can turn an inner node into a huge leaf
  std::mt19937 rng(1);
  int refused = 0, loaded = 0;
  auto attempt = [&](const std::string& bytes) {
    try {
      const FastOctTree t = io::decodeBt(bytes.data(), bytes.size(), "damaged.bt", capped);
      const std::string again = io::encodeBt(t);  // a valid map: OctoMap reads what we write of it
      std::istringstream in(again);
      octomap::OcTree check(0.1);
      EXPECT_TRUE(check.readBinary(in));
      ++loaded;
    } catch (const io::FormatError&) {
      ++refused;
    } catch (const MemoryLimitError&) {
      ++refused;
    } catch (const std::invalid_argument&) {  // an unreadable resolution or a header number gone wrong
      ++refused;
    }
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
