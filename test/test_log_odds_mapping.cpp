// The log-odds rule, checked against OctoMap 1.9 on sequences of scans: every cell's float, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <octomap/OcTree.h>
#include <Eigen/Geometry>

#include <pcl_fot/dense/fast_occ_mesh.h>
#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/octomap.h>
#include <pcl_fot/mapping/scan_insertion.h>
#include <pcl_fot/psi/psi.h>
#include <pcl_fot/search/nearest_cell_search.h>
#include <pcl_fot/tree/fast_oct_tree.h>

#include "scan_data.h"
#include "synthetic_scene.h"

namespace {

using namespace pcl::fot;

/** One scan in the map frame: its points (NaN ones kept) and the sensor's position. */
struct Scan {
  std::vector<float> xyz;
  float sensor[3];
};
using Sequence = std::vector<Scan>;

Scan placed(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Affine3f& pose) {
  Scan s;
  for (const auto& p : cloud) {
    const Eigen::Vector3f q = pose * p.getVector3fMap();
    s.xyz.insert(s.xyz.end(), {q.x(), q.y(), q.z()});
  }
  const Eigen::Vector3f t = pose.translation();
  s.sensor[0] = t.x(), s.sensor[1] = t.y(), s.sensor[2] = t.z();
  return s;
}

octomap::OcTree octomapOf(const Sequence& scans, double res, bool discretize, double max_range = -1.0) {
  octomap::OcTree tree(res);
  for (const Scan& s : scans) {
    octomap::Pointcloud cloud;
    for (std::size_t i = 0; i < s.xyz.size(); i += 3)
      if (std::isfinite(s.xyz[i]) && std::isfinite(s.xyz[i + 1]) && std::isfinite(s.xyz[i + 2]))
        cloud.push_back(s.xyz[i], s.xyz[i + 1], s.xyz[i + 2]);
    tree.insertPointCloud(cloud, octomap::point3d(s.sensor[0], s.sensor[1], s.sensor[2]), max_range, false,
                          discretize);
  }
  return tree;
}

FastOctTree oursOf(const Sequence& scans, double res, bool line_burst, bool discretize,
                   double max_range = -1.0) {
  FastOctTree tree(res);
  tree.setUpdateRule(UpdateRule::LogOdds);
  ScanOptions options;
  options.line_burst = line_burst;
  options.discretize = discretize;
  options.max_range = max_range;
  for (const Scan& s : scans) insertRays(tree, s.sensor, s.xyz.data(), s.xyz.size() / 3, 12, options);
  return tree;
}

std::uint32_t bits(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, 4);
  return b;
}

/** Every cell OctoMap knows has OctoMap's log-odds and state in ours, and ours knows no other cell. */
void expectSameLogOdds(const octomap::OcTree& om, const FastOctTree& ours) {
  std::uint64_t cells = 0, unsettled = 0;
  for (auto it = om.begin_leafs(); it != om.end_leafs(); ++it) {
    const int side = 1 << (16 - it.getDepth());
    const octomap::OcTreeKey base = it.getIndexKey();
    const float want = it->getLogOdds();
    const CellState state = om.isNodeOccupied(*it) ? CellState::Occupied : CellState::Free;
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
          const Key k{int(base[0]) - 32768 + x, int(base[1]) - 32768 + y, int(base[2]) - 32768 + z};
          ASSERT_EQ(bits(ours.getLogOdds(k)), bits(want))
              << toString(k) << ": " << ours.getLogOdds(k) << " where OctoMap has " << want;
          ASSERT_EQ(ours.getCell(k), state) << toString(k);
        }
    cells += std::uint64_t(side) * side * side;
    if (want != om.getClampingThresMinLog() && want != om.getClampingThresMaxLog())
      unsettled += side * side * side;
  }
  EXPECT_EQ(ours.getFreeCount() + ours.getOccupiedCount(), cells);
  EXPECT_EQ(ours.getUnsettledCount(), unsettled);
}

void expectSameAsOctoMap(const Sequence& scans, double res, bool discretize = false) {
  const octomap::OcTree om = octomapOf(scans, res, discretize);
  for (bool line_burst : {true, false}) {
    SCOPED_TRACE(line_burst ? "LineBurstAccess on" : "LineBurstAccess off");
    expectSameLogOdds(om, oursOf(scans, res, line_burst, discretize));
  }
}

/** The embedded room's scans, each placed by its VIEWPOINT. */
Sequence syntheticRoom() {
  Sequence scans;
  for (const auto& cloud : fot_tools::scanSyntheticRoom()) {
    const Eigen::Affine3f pose =
        Eigen::Translation3f(cloud->sensor_origin_.head<3>()) * cloud->sensor_orientation_.normalized();
    scans.push_back(placed(*cloud, pose));
  }
  return scans;
}

Eigen::Affine3f ndtGuess() {
  return Eigen::Translation3f(1.79387f, 0.720047f, 0.0f) *
         Eigen::AngleAxisf(0.6931f, Eigen::Vector3f::UnitZ());
}

Sequence roomPair() {
  return {placed(*pcl_fot_test::loadScan("room_scan1.pcd"), Eigen::Affine3f::Identity()),
          placed(*pcl_fot_test::loadScan("room_scan2.pcd"), ndtGuess())};
}

/** A wall 4 m ahead, and a box 2 m ahead in the first scan only: it has moved away by the second. */
Sequence movingObject() {
  Sequence scans;
  for (int s = 0; s < 4; ++s) {
    Scan scan{{}, {0.0f, 0.0f, 0.5f}};
    for (int i = -60; i <= 60; ++i)
      for (int j = -40; j <= 40; ++j) {
        const float dy = 0.02f * float(i), dz = 0.02f * float(j);
        const bool box = s == 0 && std::abs(dy - 0.3f) < 0.25f && std::abs(dz) < 0.25f;
        const float x = box ? 2.0f : 4.0f;
        scan.xyz.insert(scan.xyz.end(), {x, dy * x, 0.5f + dz * x});
      }
    scans.push_back(scan);
  }
  return scans;
}

PCL_FOT_SCAN_TESTS(LogOddsMappingOnScans);

TEST_P(LogOddsMappingOnScans, RoomPairAtTheNdtTutorialsGuessEqualsOctoMap) {
  expectSameAsOctoMap(roomPair(), 0.05);
}

TEST_P(LogOddsMappingOnScans, RoomPairWithAMaximumRangeEqualsOctoMap) {
  const Sequence scans = roomPair();
  expectSameLogOdds(octomapOf(scans, 0.1, false, 3.0), oursOf(scans, 0.1, true, false, 3.0));
}

TEST_P(LogOddsMappingOnScans, ThreeKinectFramesEqualOctoMap) {
  Sequence scans;
  for (const char* name : {"kinect_capture0001.pcd", "kinect_capture0002.pcd", "kinect_capture0003.pcd"})
    scans.push_back(placed(*pcl_fot_test::loadScan(name), Eigen::Affine3f::Identity()));
  expectSameAsOctoMap(scans, 0.02);
}

TEST_P(LogOddsMappingOnScans, ThreeKinectFramesDiscretizedEqualOctoMap) {
  Sequence scans;
  for (const char* name : {"kinect_capture0001.pcd", "kinect_capture0002.pcd", "kinect_capture0003.pcd"})
    scans.push_back(placed(*pcl_fot_test::loadScan(name), Eigen::Affine3f::Identity()));
  expectSameAsOctoMap(scans, 0.02, true);
}

TEST(LogOddsMapping, EmbeddedSyntheticRoomEqualsOctoMap) {
  expectSameAsOctoMap(syntheticRoom(), 0.05);
}

TEST_P(LogOddsMappingOnScans, OneScanRepeatedUntilItClampsEqualsOctoMap) {
  const Scan once = placed(*pcl_fot_test::loadScan("room_scan1.pcd"), Eigen::Affine3f::Identity());
  const Sequence scans(7, once);
  expectSameAsOctoMap(scans, 0.1);
  // Five misses or five hits reach a clamp: after three every cell carries a value, after seven none does.
  const FastOctTree three = oursOf(Sequence(3, once), 0.1, true, false);
  EXPECT_EQ(three.getUnsettledCount(), three.getFreeCount() + three.getOccupiedCount());
  FastOctTree settled = oursOf(scans, 0.1, true, false);
  EXPECT_EQ(settled.getUnsettledCount(), 0u);

  // Settled, it is the binary map of the same cells, and after shrinkToFit it costs what that map costs.
  FastOctTree binary(0.1);
  insertRays(binary, once.sensor, once.xyz.data(), once.xyz.size() / 3, 12);
  EXPECT_TRUE(settled == binary);
  const std::size_t as_inserted = settled.getMemoryBytes();
  settled.shrinkToFit();
  binary.shrinkToFit();
  EXPECT_EQ(settled.getMemoryBytes(), binary.getMemoryBytes());
  EXPECT_LT(settled.getMemoryBytes(), as_inserted);

  // Shrunk with blocks freed and leaves with values, a map takes further scans as if it had not been.
  Scan moved = once;
  moved.sensor[0] += 0.35f;  // the same points seen from elsewhere: settled cells get values again
  FastOctTree mixed = oursOf({once, once, once, once, once, moved}, 0.1, true, false);
  ASSERT_GT(mixed.getUnsettledCount(), 0u);
  FastOctTree shrunk = mixed;
  shrunk.shrinkToFit();
  EXPECT_TRUE(shrunk == mixed);
  EXPECT_LT(shrunk.getMemoryBytes(), mixed.getMemoryBytes());
  for (FastOctTree* t : {&mixed, &shrunk})
    insertRays(*t, once.sensor, moved.xyz.data(), moved.xyz.size() / 3, 12);
  EXPECT_TRUE(shrunk == mixed);
}

TEST(LogOddsMapping, AnObjectThatMovesAwayIsFreedByEvidenceEqualsOctoMap) {
  const Sequence scans = movingObject();
  expectSameAsOctoMap(scans, 0.05);
  const FastOctTree one = oursOf({scans[0]}, 0.05, true, false), all = oursOf(scans, 0.05, true, false);
  FastOctTree binary(0.05);
  const Key box{40, 6, 10};  // on the box's face, at (2.0, 0.3, 0.5)
  EXPECT_EQ(one.getCell(box), CellState::Occupied);
  EXPECT_EQ(all.getCell(box), CellState::Free) << "three misses outweigh one hit";
  EXPECT_FLOAT_EQ(all.getLogOdds(box), SensorModel().hitLogOdds() + 3 * SensorModel().missLogOdds());
}

TEST(LogOddsMapping, ScansOverCubesOfEveryKindEqualTheirCellsUpdatedOneByOne) {
  // A block that every ray of a scan passes is written as one cube where the map holds it inside one:
  // settled occupied or free, of one value, unknown. The map must equal the same cells updated one by one.
  FastOctTree start(0.05);
  start.setUpdateRule(UpdateRule::LogOdds);
  start.setBox(Key{8, -16, -16}, Key{23, 15, 15}, CellState::Occupied);
  start.setBoxLogOdds(Key{24, -16, -16}, Key{39, 15, 15}, 0.85f);
  start.setBox(Key{40, -16, -16}, Key{47, 15, 15}, CellState::Free);
  start.setBoxLogOdds(Key{48, -7, -5}, Key{53, 6, 9}, -1.2f);  // not aligned to blocks
  const float sensor[3] = {0.013f, 0.007f, -0.004f};
  std::vector<float> xyz;  // a dense frame onto a wall at x = 4 m, beyond the cubes
  for (int j = -100; j <= 100; ++j)
    for (int i = -100; i <= 100; ++i) xyz.insert(xyz.end(), {4.0f, 0.02f * float(i), 0.02f * float(j)});
  const SensorModel& model = start.getSensorModel();
  for (UpdateRule rule : {UpdateRule::LogOdds, UpdateRule::Binary})
    for (unsigned threads : {1u, 2u}) {
      ScanOptions options;
      options.rule = rule;
      options.threads = threads;
      FastOctTree scanned(start), by_cells(start);
      insertRays(scanned, sensor, xyz.data(), xyz.size() / 3, 12, options);
      std::uint64_t full = 0;
      for (const ScanBlock& b : traceScan(start, sensor, xyz.data(), xyz.size() / 3, 12, options)) {
        full += b.passed == ~std::uint64_t(0) && b.hit == 0;
        for (unsigned bit = 0; bit < 64; ++bit) {
          const Key k =
              TreeCoord(4 * b.at[0] + (bit & 3u), 4 * b.at[1] + (bit >> 2 & 3u), 4 * b.at[2] + (bit >> 4))
                  .key();
          const bool hit = (b.hit >> bit) & 1u, passed = (b.passed >> bit) & 1u;
          if (!hit && !passed) continue;
          if (rule == UpdateRule::Binary)
            by_cells.setCell(k, hit ? CellState::Occupied : CellState::Free);
          else
            by_cells.updateLogOdds(k, hit ? model.hitLogOdds() : model.missLogOdds());
        }
      }
      EXPECT_GT(full, 100u) << "blocks every ray passes";
      const FastOctTree::CanonicalPool a = scanned.canonicalPool(), b = by_cells.canonicalPool();
      EXPECT_EQ(a.words, b.words) << threads << " threads";
      ASSERT_EQ(a.values.size(), b.values.size());
      EXPECT_EQ(std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float)), 0);
    }
}

TEST(LogOddsMapping, ForEachLogOddsGivesEveryKnownCellOnceWithItsValueAndCubesWhole) {
  const Sequence once = movingObject();
  Sequence scans = once;
  scans.insert(scans.end(), once.begin(), once.end());  // eight scans: the wall and free space settle
  const FastOctTree map = oursOf(scans, 0.05, true, false);
  const SensorModel model;
  std::uint64_t cells = 0, unsettled = 0, cubes = 0;
  map.forEachLogOdds([&](const Region& r, float log_odds) {
    const std::int32_t last = (std::int32_t(1) << r.level) - 1;
    for (const Key& k : {r.min_key, Key{r.min_key.x + last, r.min_key.y + last, r.min_key.z + last}}) {
      EXPECT_EQ(bits(map.getLogOdds(k)), bits(log_odds)) << toString(k);
      EXPECT_EQ(map.getCell(k), r.state) << toString(k);
    }
    const bool settled = log_odds == model.clampMinLogOdds() || log_odds == model.clampMaxLogOdds();
    cubes += r.level > 0;
    cells += std::uint64_t(1) << (3 * r.level);
    unsettled += settled ? 0 : std::uint64_t(1) << (3 * r.level);
  });
  EXPECT_EQ(cells, map.getFreeCount() + map.getOccupiedCount());
  EXPECT_EQ(unsettled, map.getUnsettledCount());
  EXPECT_GT(unsettled, 0u) << "the box's face: one hit, then misses";
  EXPECT_GT(cubes, 0u);

  int visits = 0;
  map.forEachLogOdds([&](const Region&, float) { return ++visits < 3; });
  EXPECT_EQ(visits, 3) << "a visitor that returns false stops the walk";
}

TEST(LogOddsMapping, BinaryRuleStaysTheLatestScanPerMapOrPerCall) {
  const Sequence scans = movingObject();
  FastOctTree per_map(0.05), per_call(0.05);
  per_call.setUpdateRule(UpdateRule::LogOdds);
  ScanOptions binary;
  binary.rule = UpdateRule::Binary;
  for (const Scan& s : scans) {
    insertRays(per_map, s.sensor, s.xyz.data(), s.xyz.size() / 3, 12);
    insertRays(per_call, s.sensor, s.xyz.data(), s.xyz.size() / 3, 12, binary);
  }
  EXPECT_TRUE(per_map == per_call);
  EXPECT_EQ(per_map.getUnsettledCount(), 0u);
  EXPECT_EQ(per_map.getLogOdds(Key{80, 0, 0}), SensorModel().clampMaxLogOdds()) << "the wall, settled";
}

TEST(LogOddsMapping, TracedScansAndRegionsWriteTheWholeMapsCells) {
  // What tiled mapping (python/pcl_fot/tiles.py) rests on: a scan traced once and written later, or written a
  // region at a time, gives each cell the whole map's updates.
  const Sequence scans = syntheticRoom();
  std::vector<KeyBox> boxes;  // the level-7 nodes around key 0: the room lies inside them
  for (unsigned t = 0; t < 8; ++t) {
    const Key lo{(t & 1) ? 0 : -128, (t & 2) ? 0 : -128, (t & 4) ? 0 : -128};
    boxes.push_back(KeyBox{lo, Key{lo.x + 127, lo.y + 127, lo.z + 127}});
  }
  for (const UpdateRule rule : {UpdateRule::LogOdds, UpdateRule::Binary}) {
    ScanOptions options;
    options.rule = rule;
    FastOctTree whole(0.05), traced(0.05), stitched(0.05);
    std::vector<FastOctTree> tiles(boxes.size(), FastOctTree(0.05));
    std::size_t outside = 0;
    for (const Scan& s : scans) {
      const std::size_t n = s.xyz.size() / 3;
      insertRays(whole, s.sensor, s.xyz.data(), n, 12, options);
      const std::vector<ScanBlock> blocks = traceScan(traced, s.sensor, s.xyz.data(), n, 12, options);
      applyScan(traced, blocks.data(), blocks.size(), options);
      for (std::size_t t = 0; t < boxes.size(); ++t) {
        ScanOptions tile = options;
        tile.region = boxes[t];
        outside += insertRays(tiles[t], s.sensor, s.xyz.data(), n, 12, tile).outside_region;
      }
    }
    for (std::size_t t = 0; t < boxes.size(); ++t) {
      tiles[t].forEachRegion([&](const Region& r) {
        const std::int32_t edge = (std::int32_t(1) << r.level) - 1;
        EXPECT_TRUE(boxes[t].contains(r.min_key) &&
                    boxes[t].contains(Key{r.min_key.x + edge, r.min_key.y + edge, r.min_key.z + edge}));
        return true;
      });
      stitched.merge(tiles[t]);
    }
    EXPECT_GT(whole.getOccupiedCount(), 1000u);
    EXPECT_TRUE(traced == whole) << "rule " << int(rule);
    EXPECT_TRUE(stitched == whole) << "rule " << int(rule);
    EXPECT_GT(outside, 0u) << "rays that cannot reach a tile are not walked";
  }
  FastOccMesh grid(CellGrid(0.05), 64);
  ScanOptions region;
  region.region = boxes[0];
  EXPECT_THROW(insertRays(grid, scans[0].sensor, scans[0].xyz.data(), 1, 12, region), std::invalid_argument);
}

TEST_P(LogOddsMappingOnScans, MergeEqualsTheMapOfAllScansAndRefusesAnotherGrid) {
  const Sequence scans = roomPair();
  FastOctTree merged = oursOf({scans[0]}, 0.05, true, false);
  merged.merge(oursOf({scans[1]}, 0.05, true, false));
  EXPECT_TRUE(merged == oursOf(scans, 0.05, true, false));

  // OctoMap users merge by updateNode(key, value) for each leaf of the other map: the same floats.
  octomap::OcTree a = octomapOf({scans[0]}, 0.05, false);
  const octomap::OcTree b = octomapOf({scans[1]}, 0.05, false);
  for (auto it = b.begin_leafs(); it != b.end_leafs(); ++it) {
    const int side = 1 << (16 - it.getDepth());
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
          const octomap::OcTreeKey k = it.getIndexKey();
          a.updateNode(octomap::OcTreeKey(k[0] + x, k[1] + y, k[2] + z), it->getLogOdds());
        }
  }
  expectSameLogOdds(a, merged);

  const FastOctTree before = merged;
  EXPECT_THROW(merged.merge(FastOctTree(0.1)), std::invalid_argument);
  EXPECT_THROW(merged.merge(FastOctTree(0.05, 0.01)), std::invalid_argument);
  EXPECT_TRUE(merged == before);
}

PCL_FOT_SCAN_TESTS(LogOddsFilesOnScans);

TEST_P(LogOddsFilesOnScans, OtRoundTripsThroughOctoMapKeepEveryValue) {
  const Sequence scans = roomPair();
  const FastOctTree ours = oursOf(scans, 0.05, true, false);
  // Ours written, OctoMap reads the same value in every leaf.
  std::istringstream written(io::encodeOt(ours));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(written));
  auto* om = dynamic_cast<octomap::OcTree*>(read.get());
  ASSERT_NE(om, nullptr);
  expectSameLogOdds(*om, ours);
  // OctoMap's written, ours reads them all, and writes them back as they came.
  std::ostringstream theirs;
  octomapOf(scans, 0.05, false).write(theirs);
  const std::string bytes = theirs.str();
  const FastOctTree back = io::decodeOt(bytes.data(), bytes.size());
  EXPECT_TRUE(back == ours);
  const std::string again = io::encodeOt(back);
  EXPECT_TRUE(io::decodeOt(again.data(), again.size()) == ours);
}

TEST(LogOddsFiles, BtExportIsOctoMapsWriteBinaryByteForByte) {
  const Sequence scans = movingObject();
  octomap::OcTree om = octomapOf(scans, 0.05, false);
  std::ostringstream theirs;
  om.writeBinary(theirs);  // toMaxLikelihood, prune, write
  const FastOctTree ours = oursOf(scans, 0.05, true, false);
  ASSERT_GT(ours.getUnsettledCount(), 0u);
  EXPECT_EQ(io::encodeBt(ours), theirs.str());
  FastOctTree settled = ours;
  settled.toMaxLikelihood();
  EXPECT_EQ(settled.getUnsettledCount(), 0u);
  EXPECT_EQ(settled.getValueRowCount(), 0u);
  EXPECT_EQ(settled.getValueLeafCount(), 0u);
  EXPECT_EQ(settled.getOccupiedCount(), ours.getOccupiedCount());
  EXPECT_EQ(io::encodeBt(settled), theirs.str());
}

TEST(LogOddsStorage, PaletteLeavesRowsAndFullPaletteKeepEveryFloat) {
  FastOctTree tree(0.1);
  // 20000 leaves, one cell each, each its own value: the palette (16383 values) fills, rows take the rest.
  std::vector<float> values;
  for (int i = 0; i < 20000; ++i) {
    values.push_back(-1.9f + 3.0f * float(i) / 20000.0f);
    tree.setLogOdds(Key{2 * (i % 100), 2 * (i / 100), 0}, values.back());
  }
  // One leaf with two values needs a row; -0.0 and 0.0 are different floats.
  tree.setLogOdds(Key{1000, 0, 0}, 0.0f);
  tree.setLogOdds(Key{1001, 0, 0}, -0.0f);
  EXPECT_EQ(tree.getValueLeafCount(), 20001u);
  EXPECT_GT(tree.getValueRowCount(), 20000u - 16383u);
  EXPECT_LT(tree.getValueRowCount(), 20001u - 16000u);
  const std::string bytes = io::encodeFot(tree);
  const FastOctTree back = io::decodeFot(bytes.data(), bytes.size());
  const FastOctTree* both[] = {&tree, &back};
  for (const FastOctTree* t : both) {
    for (int i = 0; i < 20000; ++i)
      ASSERT_EQ(bits(t->getLogOdds(Key{2 * (i % 100), 2 * (i / 100), 0})), bits(values[i])) << i;
    EXPECT_EQ(bits(t->getLogOdds(Key{1000, 0, 0})), bits(0.0f));
    EXPECT_EQ(bits(t->getLogOdds(Key{1001, 0, 0})), bits(-0.0f));
    EXPECT_TRUE(std::isnan(t->getLogOdds(Key{1, 0, 0})));
  }
  EXPECT_TRUE(back == tree);
  EXPECT_EQ(io::encodeFot(back), bytes);
  // A row leaf that settles, and a palette leaf that settles, give their storage back.
  tree.setCell(Key{1000, 0, 0}, CellState::Occupied);
  tree.setCell(Key{1001, 0, 0}, CellState::Occupied);
  tree.setCell(Key{0, 0, 0}, CellState::Free);
  EXPECT_EQ(tree.getValueLeafCount(), 19999u);
  const std::size_t held = tree.getMemoryBytes();
  const FastOctTree before = tree;
  tree.shrinkToFit();
  EXPECT_LE(tree.getMemoryBytes(), held);
  EXPECT_TRUE(tree == before);
  EXPECT_EQ(tree.getLogOdds(Key{0, 0, 0}), SensorModel().clampMinLogOdds());
}

TEST(LogOddsStorage, LeavesOfSeveralValuesTakeBytesWhileThePaletteIsShort) {
  FastOctTree tree(0.1);
  tree.setLogOdds(Key{0, 0, 0}, 0.5f);
  tree.setLogOdds(Key{1, 0, 0}, -0.5f);  // two values in one leaf: a row of palette indices
  EXPECT_EQ(tree.getValueRowCount(), 1u);
  for (int i = 0; i < 300; ++i) tree.setLogOdds(Key{4 + 2 * i, 0, 0}, 0.001f * float(i + 1));
  tree.setLogOdds(Key{0, 1, 0}, 0.299f);  // a value past the palette's first 255: the leaf takes floats
  tree.setLogOdds(Key{1, 1, 0}, 0.3f);
  EXPECT_EQ(tree.getValueRowCount(), 1u) << "the leaf kept one row, of another kind";
  EXPECT_EQ(tree.getLogOdds(Key{0, 0, 0}), 0.5f);
  EXPECT_EQ(tree.getLogOdds(Key{1, 0, 0}), -0.5f);
  EXPECT_EQ(tree.getLogOdds(Key{0, 1, 0}), 0.299f);
  EXPECT_EQ(tree.getLogOdds(Key{1, 1, 0}), 0.3f);
  EXPECT_EQ(tree.getLogOdds(Key{4 + 2 * 299, 0, 0}), 0.3f);
  const std::string bytes = io::encodeFot(tree);
  EXPECT_TRUE(io::decodeFot(bytes.data(), bytes.size()) == tree);
  tree.setLogOdds(Key{0, 1, 0}, 0.3f);  // one value again: no row
  tree.setLogOdds(Key{0, 0, 0}, 0.3f);
  tree.setLogOdds(Key{1, 0, 0}, 0.3f);
  EXPECT_EQ(tree.getValueRowCount(), 0u);
  EXPECT_EQ(tree.getUnsettledCount(), 304u);
}

TEST(LogOddsStorage, ACubeOfOneValueIsOneWordAtAnyLevelWhateverTheOrderOfWrites) {
  const float miss = SensorModel().missLogOdds();
  FastOctTree cube(0.1), by_cells(0.1);
  cube.setBoxLogOdds(Key{0, 0, 0}, Key{31, 31, 31}, miss);
  for (int z = 31; z >= 0; --z)  // cell by cell, in the opposite order
    for (int y = 31; y >= 0; --y)
      for (int x = 31; x >= 0; --x) by_cells.setLogOdds(Key{x, y, z}, miss);
  for (const FastOctTree* t : {&cube, &by_cells}) {
    EXPECT_EQ(t->getBlockCount(), 0u) << "the 32^3 cells fold into the root word";
    EXPECT_EQ(t->getValueLeafCount(), 1u);
    EXPECT_EQ(t->getUnsettledCount(), 32768u);
    EXPECT_EQ(t->getFreeCount(), 32768u);
  }
  EXPECT_TRUE(cube == by_cells);
  EXPECT_EQ(cube.canonicalPool().words, by_cells.canonicalPool().words);
  int regions = 0;
  cube.forEachLogOdds([&](const Region& r, float v) {
    EXPECT_EQ(r.level, 5u);
    EXPECT_EQ(bits(v), bits(miss));
    ++regions;
  });
  EXPECT_EQ(regions, 1);

  // A cell that moves splits the cube down to its leaf; setting it back folds it again.
  const FastOctTree whole = cube;
  cube.updateLogOdds(Key{3, 7, 9}, 0.85f);
  EXPECT_EQ(cube.getBlockCount(), 4u);
  EXPECT_EQ(bits(cube.getLogOdds(Key{3, 7, 9})), bits(miss + 0.85f));
  EXPECT_EQ(bits(cube.getLogOdds(Key{2, 7, 9})), bits(miss));
  EXPECT_EQ(bits(cube.getLogOdds(Key{0, 31, 0})), bits(miss));
  EXPECT_EQ(cube.getUnsettledCount(), 32768u);
  cube.setLogOdds(Key{3, 7, 9}, miss);
  EXPECT_TRUE(cube == whole);
  EXPECT_EQ(cube.getBlockCount(), 0u);
  // A settled cell inside splits it as well; part of the cube erased leaves the rest of one value.
  cube.setCell(Key{16, 16, 16}, CellState::Occupied);
  EXPECT_EQ(cube.getUnsettledCount(), 32767u);
  cube.setBoxLogOdds(Key{0, 0, 0}, Key{31, 31, 15}, FastOctTree::kUnknownValue);
  EXPECT_EQ(cube.getFreeCount(), 16383u);
  cube.setLogOdds(Key{16, 16, 16}, miss);
  EXPECT_EQ(cube.getBlockCount(), 0u) << "the known half is four octants of the root word";
  EXPECT_EQ(bits(cube.getLogOdds(Key{31, 31, 31})), bits(miss));
  EXPECT_THROW(cube.setBoxLogOdds(Key{0, 0, 0}, Key{1, 1, 1}, INFINITY), std::invalid_argument);

  // A cell far away grows the root, and erased leaves the cube an octant of a larger word: the same map.
  FastOctTree grown = whole;
  grown.setLogOdds(Key{100, 0, 0}, 0.3f);
  grown.setCell(Key{100, 0, 0}, CellState::Unknown);
  EXPECT_TRUE(grown == whole);
  EXPECT_EQ(grown.canonicalPool().words, whole.canonicalPool().words);
  EXPECT_EQ(io::encodeOt(grown), io::encodeOt(whole));

  // Merged, the cube stays one word; settled, it is its binary twin.
  FastOctTree twice = whole;
  twice.merge(whole);
  EXPECT_EQ(twice.getBlockCount(), 0u);
  EXPECT_EQ(bits(twice.getLogOdds(Key{5, 5, 5})), bits(miss + miss));
  twice.toMaxLikelihood();
  FastOctTree binary(0.1);
  binary.setBox(Key{0, 0, 0}, Key{31, 31, 31}, CellState::Free);
  EXPECT_TRUE(twice == binary);
  twice.shrinkToFit();
  EXPECT_EQ(twice.getMemoryBytes(), binary.getMemoryBytes());

  // Files keep the cube whole; a .fot pool that spells it out as leaves (as files did before) folds.
  for (const std::string& bytes : {io::encodeFot(whole), io::encodeOt(whole)}) {
    const FastOctTree back = bytes[0] == '#' ? io::decodeOt(bytes.data(), bytes.size())
                                             : io::decodeFot(bytes.data(), bytes.size());
    EXPECT_TRUE(back == whole);
    EXPECT_EQ(back.getBlockCount(), 0u);
  }
  FastOctTree::CanonicalPool leaves = whole.canonicalPool();
  leaves.words = {node::reference(1), 0, 0, 0, 0, 0, 0, 0};
  leaves.values.clear();
  for (unsigned o = 0; o < 8; ++o) {
    leaves.words.push_back(node::uniform(CellState::Free) | node::kValueFlag);
    leaves.values.insert(leaves.values.end(), 8, miss);
  }
  leaves.root_level = 2;
  leaves.root_base = TreeCoord(Key{0, 0, 0});
  const FastOctTree folded = FastOctTree::fromCanonicalPool(whole.getGrid(), leaves);
  EXPECT_EQ(folded.getBlockCount(), 0u);
  EXPECT_EQ(folded.getValueLeafCount(), 1u);
  EXPECT_EQ(bits(folded.getLogOdds(Key{3, 3, 3})), bits(miss));
}

TEST(LogOddsFiles, AnOtWhoseRootIsOneLeafBetweenTheClampsIsOneWord) {
  // OctoMap prunes a cube of one value to a leaf at any depth: here its root, 2^48 cells.
  std::ostringstream root_leaf;
  root_leaf << "# Octomap OcTree file\nid OcTree\nsize 1\nres 0.1\ndata\n";
  const float value = 0.5f;
  root_leaf.write(reinterpret_cast<const char*>(&value), 4);
  root_leaf.put(0);
  const std::string bytes = root_leaf.str();
  std::istringstream in(bytes);
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(in));
  auto* theirs = dynamic_cast<octomap::OcTree*>(read.get());
  ASSERT_NE(theirs, nullptr) << "OctoMap reads it";
  ASSERT_EQ(theirs->getNumLeafNodes(), 1u);
  const FastOctTree ours = io::decodeOt(bytes.data(), bytes.size());
  EXPECT_EQ(ours.getBlockCount(), 0u);
  EXPECT_EQ(ours.getOccupiedCount(), std::uint64_t(1) << 48);
  EXPECT_EQ(ours.getUnsettledCount(), std::uint64_t(1) << 48);
  for (const Key& k : {Key{-32768, -32768, -32768}, Key{32767, 32767, 32767}, Key{5, -9, 77}})
    EXPECT_EQ(bits(ours.getLogOdds(k)), bits(value)) << toString(k);
  EXPECT_TRUE(std::isnan(ours.getLogOdds(Key{32768, 0, 0})));
  const std::string again = io::encodeOt(ours);
  EXPECT_NE(again.find("\nsize 1\n"), std::string::npos);
  EXPECT_EQ(again.substr(again.size() - 5), bytes.substr(bytes.size() - 5));
}

TEST(LogOddsMapping, SearchPsiAndExportsReadTheThresholdedMap) {
  const FastOctTree ours = oursOf(movingObject(), 0.05, true, false);
  ASSERT_GT(ours.getValueLeafCount(), 0u);
  FastOctTree settled = ours;
  settled.toMaxLikelihood();
  for (CellState target : {CellState::Occupied, CellState::Free}) {
    std::vector<Key> a, b;
    ours.forEachCell(target, [&](const Key& k) { a.push_back(k); });
    settled.forEachCell(target, [&](const Key& k) { b.push_back(k); });
    EXPECT_EQ(a, b);
    for (Metric metric : {Metric::Manhattan, Metric::Euclidean}) {
      NearestCellSearch in_ours(ours, metric, target), in_settled(settled, metric, target);
      for (int i = 0; i < 200; ++i) {
        const Key q{(i * 37) % 90 - 5, (i * 53) % 120 - 60, (i * 29) % 60 - 10};
        CellMatch m, n;
        ASSERT_EQ(in_ours.nearest(q, m), in_settled.nearest(q, n));
        EXPECT_EQ(m.key, n.key);
        EXPECT_EQ(m.distance, n.distance);
      }
    }
  }
  const FastOctTree other = oursOf({movingObject()[0]}, 0.05, true, false);
  EXPECT_EQ(psi(ours, other).sum, psi(settled, other).sum);
  EXPECT_EQ(psi(other, ours).sum, psi(other, settled).sum);
}

TEST(SensorModel, OctoMapsDefaultsAndFloats) {
  const SensorModel m;
  octomap::OcTree om(0.1);
  EXPECT_EQ(bits(m.hitLogOdds()), bits(om.getProbHitLog()));
  EXPECT_EQ(bits(m.missLogOdds()), bits(om.getProbMissLog()));
  EXPECT_EQ(bits(m.clampMinLogOdds()), bits(om.getClampingThresMinLog()));
  EXPECT_EQ(bits(m.clampMaxLogOdds()), bits(om.getClampingThresMaxLog()));
  EXPECT_EQ(bits(m.occupancyLogOdds()), bits(om.getOccupancyThresLog()));
}

TEST(SensorModel, ValuesThatMakeNoSenseAreRefusedAndNothingChanges) {
  const double nan = std::nan("");
  EXPECT_THROW(SensorModel(1.0), std::invalid_argument);
  EXPECT_THROW(SensorModel(0.7, 0.0), std::invalid_argument);
  EXPECT_THROW(SensorModel(nan, 0.4), std::invalid_argument);
  EXPECT_THROW(SensorModel(0.7, 0.4, 0.97, 0.12), std::invalid_argument) << "clamp min above clamp max";
  EXPECT_THROW(SensorModel(0.4, 0.4), std::invalid_argument) << "a hit that lowers the log-odds";
  EXPECT_THROW(SensorModel(0.7, 0.6), std::invalid_argument) << "a miss that raises it";
  EXPECT_THROW(SensorModel(0.7, 0.4, 0.6, 0.971, 0.5), std::invalid_argument)
      << "the threshold below the clamps";

  FastOctTree tree(0.1);
  tree.setCell(Key{1, 2, 3}, CellState::Occupied);
  EXPECT_THROW(tree.setSensorModel(SensorModel(0.7, 0.4, 0.2)), std::logic_error);
  EXPECT_EQ(tree.getSensorModel(), SensorModel());
  tree.setSensorModel(SensorModel(0.9, 0.2));  // hit and miss may change
  EXPECT_FLOAT_EQ(tree.getSensorModel().probHit(), 0.9);
  EXPECT_THROW(tree.updateLogOdds(Key{0, 0, 0}, std::nanf("")), std::invalid_argument);
  EXPECT_THROW(tree.setLogOdds(Key{kMaxKey + 1, 0, 0}, 1.0f), std::out_of_range);
}

}  // namespace

namespace {

TEST(LogOddsStorage, AnUpdatePastTheMemoryCapChangesNothing) {
  int refused = 0;
  // Around the room a value page takes, so that some caps refuse the expansion and some the page.
  for (std::size_t cap = 20000; cap <= 21500; cap += 8) {
    FastOctTree tree(0.1);
    tree.setBox(Key{0, 0, 0}, Key{1023, 1023, 1023}, CellState::Free);  // settled: one word
    tree.setCell(Key{100, 0, 0}, CellState::Occupied);
    tree.setMaxMemoryBytes(cap);
    const FastOctTree before = tree;
    try {
      tree.updateLogOdds(Key{5, 6, 7}, SensorModel().hitLogOdds());  // expands the cube down to a leaf
      tree.updateLogOdds(Key{9, 6, 7}, 0.25f);
    } catch (const MemoryLimitError&) {
      ++refused;
      EXPECT_TRUE(tree == before || tree.getLogOdds(Key{5, 6, 7}) != before.getLogOdds(Key{5, 6, 7}));
    }
    // Whatever happened, the tree is canonical: its pool passes the loader's checks.
    const std::string bytes = io::encodeFot(tree);
    EXPECT_NO_THROW(io::decodeFot(bytes.data(), bytes.size())) << "cap " << cap;
  }
  EXPECT_GT(refused, 10);
}

}  // namespace
