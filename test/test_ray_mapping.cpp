// Ray tracing and scan insertion, checked cell for cell against OctoMap on real scans.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <thread>
#include <tuple>
#include <vector>

#include <octomap/OcTree.h>
#include <pcl/common/transforms.h>

#include <pcl_fot/dense/fast_occ_mesh.h>
#include <pcl_fot/mapping/cast_ray.h>
#include <pcl_fot/mapping/ray_traversal.h>
#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/tree/fast_oct_tree.h>

#include "mapping/block_ray_walker.h"
#include "scan_data.h"

using namespace pcl::fot;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace {

constexpr int kOctoMapKeyOffset = 32768;

/** A real scan in its map frame: its VIEWPOINT applied, as insertScan does. */
Cloud::Ptr scanInMapFrame(const std::string& name) {
  const auto raw = pcl_fot_test::loadScan(name);
  const Eigen::Affine3f pose = Eigen::Translation3f(raw->sensor_origin_.head<3>()) * raw->sensor_orientation_;
  Cloud::Ptr out(new Cloud);
  pcl::transformPointCloud(*raw, *out, pose);
  return out;
}

Key fromOctoMap(const octomap::OcTreeKey& k) {
  return Key{int(k[0]) - kOctoMapKeyOffset, int(k[1]) - kOctoMapKeyOffset, int(k[2]) - kOctoMapKeyOffset};
}

std::vector<Key> ourRay(const CellGrid& grid, const float o[3], const float e[3]) {
  std::vector<Key> keys;
  const std::size_t cells = traceSegment(grid, o, e, [&](const Key& k) { keys.push_back(k); });
  EXPECT_EQ(cells, keys.size());
  return keys;
}

void expectSameRaysAsOctoMap(const Cloud& cloud, double res, const float origin[3]) {
  octomap::OcTree reference(res);
  octomap::KeyRay ray;
  const CellGrid grid(res);
  std::size_t rays = 0, keys = 0;
  for (const auto& p : cloud) {
    if (!std::isfinite(p.x)) continue;
    ASSERT_TRUE(reference.computeRayKeys(octomap::point3d(origin[0], origin[1], origin[2]),
                                         octomap::point3d(p.x, p.y, p.z), ray));
    const float end[3] = {p.x, p.y, p.z};
    const std::vector<Key> ours = ourRay(grid, origin, end);
    ASSERT_EQ(ours.size(), ray.size())
        << "ray " << rays << " to (" << p.x << ", " << p.y << ", " << p.z << ")";
    std::size_t i = 0;
    for (const auto& k : ray) ASSERT_EQ(ours[i++], fromOctoMap(k)) << "ray " << rays << " cell " << i - 1;
    ++rays;
    keys += ray.size();
  }
  EXPECT_GT(rays, 10000u);
  EXPECT_GT(keys, rays * 10) << "the rays must be long enough to mean something";
}

/** The cells OctoMap's tree knows, expanded from its (possibly pruned) leaves. */
void octomapCells(const octomap::OcTree& tree, std::vector<Key>& occupied, std::vector<Key>& free) {
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const int side = 1 << (tree.getTreeDepth() - it.getDepth());
    const octomap::OcTreeKey base = it.getIndexKey();
    auto& out = tree.isNodeOccupied(*it) ? occupied : free;
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
          const Key k = fromOctoMap(base);
          out.push_back(Key{k.x + x, k.y + y, k.z + z});
        }
  }
}

void expectSameMapAsOctoMap(const Cloud& cloud, double res, double max_range) {
  const float sensor[3] = {0, 0, 0};
  octomap::OcTree reference(res);
  octomap::Pointcloud scan;
  for (const auto& p : cloud)
    if (std::isfinite(p.x)) scan.push_back(p.x, p.y, p.z);
  reference.insertPointCloud(scan, octomap::point3d(0, 0, 0), max_range);

  FastOctTree tree(res);
  ScanOptions options;
  options.max_range = max_range;
  const ScanStats stats = insertRays(tree, sensor, &cloud[0].x, cloud.size(), sizeof(pcl::PointXYZ), options);
  EXPECT_EQ(stats.rays, scan.size());

  std::vector<Key> occupied, free;
  octomapCells(reference, occupied, free);
  EXPECT_EQ(tree.getOccupiedCount(), occupied.size());
  EXPECT_EQ(tree.getFreeCount(), free.size());
  for (const Key& k : occupied) ASSERT_EQ(tree.getCell(k), CellState::Occupied) << toString(k);
  for (const Key& k : free) ASSERT_EQ(tree.getCell(k), CellState::Free) << toString(k);
  EXPECT_GT(free.size(), occupied.size());
}

}  // namespace

PCL_FOT_SCAN_TESTS(RayCasterOnScans);

TEST_P(RayCasterOnScans, SameCellsAsOctoMapOnEveryRayOfRoomScan1At5cm) {
  const float origin[3] = {0, 0, 0};
  expectSameRaysAsOctoMap(*scanInMapFrame("room_scan1.pcd"), 0.05, origin);
}

TEST_P(RayCasterOnScans, SameCellsAsOctoMapOnEveryRayOfAKinectFrameAt1cm) {
  const float origin[3] = {0, 0, 0};
  expectSameRaysAsOctoMap(*scanInMapFrame("kinect_capture0001.pcd"), 0.01, origin);
}

TEST_P(RayCasterOnScans, SameCellsAsOctoMapFromAnOffCentreSensor) {
  const float origin[3] = {0.337f, -1.2049f, 0.71f};  // not on any cell boundary
  expectSameRaysAsOctoMap(*scanInMapFrame("room_scan2.pcd"), 0.05, origin);
}

TEST(RayCaster, SegmentEndsExcludeTheEndCell) {
  const CellGrid grid(1.0);
  const float o[3] = {0.5f, 0.5f, 0.5f}, e[3] = {4.5f, 0.5f, 0.5f};
  const std::vector<Key> keys = ourRay(grid, o, e);
  ASSERT_EQ(keys.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(keys[i], (Key{i, 0, 0}));
  EXPECT_TRUE(ourRay(grid, o, o).empty()) << "a ray inside one cell visits nothing";
  const float nan[3] = {std::nanf(""), 0, 0};
  EXPECT_EQ(traceSegment(grid, o, nan, [](const Key&) { ADD_FAILURE(); }), 0u);
}

TEST(BlockRayWalker, BlockCellsGatherEachLeafsCellsInOctantOrder) {
  namespace bc = detail::block_cells;
  for (unsigned x = 0; x < 4; ++x)
    for (unsigned y = 0; y < 4; ++y)
      for (unsigned z = 0; z < 4; ++z) {
        const unsigned bit = bc::bit(x, y, z), leaf = tree_coord::octant(x, y, z, 2);
        const std::uint64_t cell = std::uint64_t(1) << bit;
        EXPECT_EQ(bc::leafOf(bit), leaf);
        EXPECT_NE(bc::leafBits(leaf) & cell, 0u);
        EXPECT_EQ(bc::leafMask(cell, leaf), 1u << tree_coord::octant(x, y, z, 1));
        EXPECT_EQ(bc::leafMask(~cell, leaf), 0xFFu & ~(1u << tree_coord::octant(x, y, z, 1)));
      }
  std::uint64_t all = 0;
  for (unsigned leaf = 0; leaf < 8; ++leaf) all += bc::leafBits(leaf);
  EXPECT_EQ(all, ~std::uint64_t(0)) << "the leaves tile the block";
}

TEST(BlockRayWalker, StretchesAreEachRaysCellsSplitAtEveryBlockChange) {
  using detail::BlockRayWalker;
  using Stretch = std::array<std::uint64_t, 4>;  // block x, y, z and cells
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-3.0f, 3.0f);
  for (double res : {0.01, 0.05, 0.0625, 0.3}) {
    const CellGrid grid(res);
    // A sensor anywhere, and one at a cell centre: from there, at a power-of-two resolution, exact
    // diagonals tie at every crossing.
    const float centre = float(0.5 * res);
    for (const std::array<float, 3>& at : {std::array<float, 3>{coord(rng), coord(rng), coord(rng)},
                                           std::array<float, 3>{centre, centre, centre}}) {
      const float* sensor = at.data();
      // Rays of every length, a fan of neighbours as a scan has, and one inside the sensor's cell.
      std::vector<float> ends;
      for (int r = 0; r < 500; ++r)
        for (float c : {coord(rng), coord(rng), coord(rng)}) ends.push_back(c);
      for (int r = 0; r < 200; ++r)
        for (float c : {2.5f + 0.001f * float(r), -1.0f + 0.002f * float(r), 0.3f}) ends.push_back(c);
      ends.insert(ends.end(), sensor, sensor + 3);
      for (int k = 1; k < 40; ++k)
        for (const auto& d : {std::array<int, 3>{k, k, 0}, {0, k, -k}, {-k, 0, k}, {k, -k, k}})
          for (int i = 0; i < 3; ++i) ends.push_back(sensor[i] + float(d[i] * res));
      const std::size_t rays = ends.size() / 3;

      // The expected stretches: maximal runs of one ray's consecutive cells in one 4×4×4 block.
      std::vector<Stretch> expected;
      std::uint64_t cells = 0;
      for (std::size_t r = 0; r < rays; ++r) {
        const std::vector<Key> walk = ourRay(grid, sensor, &ends[3 * r]);
        cells += walk.size();
        for (std::size_t i = 0; i < walk.size(); ++i) {
          const std::uint32_t u[3] = {tree_coord::fromKey(walk[i].x), tree_coord::fromKey(walk[i].y),
                                      tree_coord::fromKey(walk[i].z)};
          const std::uint64_t bit = std::uint64_t(1)
                                    << detail::block_cells::bit(u[0] & 3u, u[1] & 3u, u[2] & 3u);
          const Stretch s{u[0] >> 2, u[1] >> 2, u[2] >> 2, bit};
          if (i > 0 && std::equal(s.begin(), s.begin() + 3, expected.back().begin()))
            expected.back()[3] |= bit;
          else
            expected.push_back(s);
        }
      }
      std::sort(expected.begin(), expected.end());

      for (BlockRayWalker::Lanes lanes :
           {BlockRayWalker::Lanes::Best, BlockRayWalker::Lanes::Avx2, BlockRayWalker::Lanes::Scalar}) {
        BlockRayWalker walker(grid, sensor, ends.data(), rays, lanes);
        std::vector<Stretch> got;
        while (const std::size_t n = walker.next())
          for (std::size_t i = 0; i < n; ++i) {
            std::uint32_t b[3];
            walker.block(walker.blockKey(i), b);
            got.push_back({b[0], b[1], b[2], walker.cells(i)});
          }
        EXPECT_EQ(walker.cellCount(), cells);
        std::sort(got.begin(), got.end());
        EXPECT_TRUE(got == expected) << "lanes " << int(lanes) << " at " << res << " m: " << got.size()
                                     << " stretches, expected " << expected.size();
      }
    }
  }
}

PCL_FOT_SCAN_TESTS(ScanInsertionOnScans);

TEST_P(ScanInsertionOnScans, SameFreeAndOccupiedCellsAsOctoMapOnRoomScan1) {
  expectSameMapAsOctoMap(*scanInMapFrame("room_scan1.pcd"), 0.05, -1.0);
}

TEST_P(ScanInsertionOnScans, SameFreeAndOccupiedCellsAsOctoMapOnAKinectFrame) {
  expectSameMapAsOctoMap(*scanInMapFrame("kinect_capture0002.pcd"), 0.01, -1.0);
}

TEST_P(ScanInsertionOnScans, SameCellsAsOctoMapWithAMaximumRange) {
  expectSameMapAsOctoMap(*scanInMapFrame("room_scan2.pcd"), 0.05, 4.0);
}

TEST_P(ScanInsertionOnScans, TreeAndGridAgreeCellForCell) {
  const auto cloud = pcl_fot_test::loadScan("kinect_capture0003.pcd");
  const CellGrid vg(0.02);
  FastOctTree tree(vg), tree_plain(vg);
  FastOccMesh grid(vg, 512);
  ScanOptions plain;
  plain.line_burst = false;
  const ScanStats a = insertScan(tree, *cloud);
  const ScanStats b = insertScan(grid, *cloud);
  const ScanStats c = insertScan(tree_plain, *cloud, plain);
  EXPECT_EQ(a.ray_cells, b.ray_cells);
  EXPECT_EQ(a.ray_cells, c.ray_cells);
  EXPECT_GT(a.ray_cells, 10 * a.occupied);
  EXPECT_TRUE(tree == tree_plain) << "LineBurstAccess on and off give the same map";
  EXPECT_EQ(tree.getOccupiedCount(), grid.getOccupiedCount());
  EXPECT_EQ(tree.getFreeCount(), grid.getFreeCount());
  for (CellState s : {CellState::Occupied, CellState::Free})
    grid.forEachCell(s, [&](const Key& k) { ASSERT_EQ(tree.getCell(k), s) << toString(k); });
}

TEST(ScanInsertion, LineBurstOnAndOffAgreeOnTheBlocksTheWriterRemembers) {
  // Long rays along each axis, and cones of shorter ones around them, so that the writer's small table of
  // written blocks (one entry per ray) keeps meeting blocks that differ in one coordinate only.
  Cloud cloud;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> spread(-0.08f, 0.08f);
  for (int axis = 0; axis < 3; ++axis)
    for (int i = 0; i < 200; ++i) {
      float p[3] = {spread(rng), spread(rng), spread(rng)};
      p[axis] = (i % 2 ? 1.0f : -1.0f) * (3.0f + spread(rng));
      if (i < 2) p[(axis + 1) % 3] = p[(axis + 2) % 3] = 0.005f, p[axis] *= 8.0f;
      cloud.push_back(pcl::PointXYZ(p[0], p[1], p[2]));
    }
  FastOctTree tree(0.01), tree_plain(0.01);
  ScanOptions plain;
  plain.line_burst = false;
  for (int scan = 0; scan < 2; ++scan) {  // the second scan finds its leaves written already
    const ScanStats a = insertScan(tree, cloud), b = insertScan(tree_plain, cloud, plain);
    EXPECT_EQ(a.ray_cells, b.ray_cells);
    ASSERT_TRUE(tree == tree_plain) << "scan " << scan;
  }
  EXPECT_GT(tree.getFreeCount(), 50000u);
}

namespace {

/** A depth camera's frame of a scene with a slanted floor, a wall and a box in front: `w` x `h` rays. */
std::vector<float> depthFrame(const float sensor[3], int w, int h) {
  std::vector<float> xyz;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float d[3] = {1.1f * (float(x) / float(w - 1) - 0.5f), 0.8f * (float(y) / float(h - 1) - 0.5f),
                          1.0f};
      float t = 3.0f;                                                          // the wall
      if (d[1] > 0.05f) t = std::min(t, 0.9f / d[1]);                          // the floor, seen at a slant
      if (std::fabs(d[0] - 0.1f) < 0.12f && std::fabs(d[1]) < 0.1f) t = 1.2f;  // the box
      for (int a = 0; a < 3; ++a) xyz.push_back(sensor[a] + t * d[a]);
    }
  return xyz;
}

/** traceScan's cells against the union of traceSegment's over the rays, plus the endpoints. */
void expectPlainWalksUnion(const std::vector<float>& xyz, const float sensor[3], double res, unsigned threads,
                           double min_skipped) {
  FastOctTree map(res);
  ScanOptions options;
  options.threads = threads;
  ScanStats stats;
  const std::vector<ScanBlock> blocks =
      traceScan(map, sensor, xyz.data(), xyz.size() / 3, 3 * sizeof(float), options, &stats);
  std::vector<Key> got_passed, got_hit, passed, hit;
  for (const ScanBlock& b : blocks)
    for (unsigned bit = 0; bit < 64; ++bit) {
      const Key k = detail::block_cells::cellKey(b.at, bit);
      if (b.hit >> bit & 1u)
        got_hit.push_back(k);
      else if (b.passed >> bit & 1u)
        got_passed.push_back(k);
    }
  const CellGrid& grid = map.getGrid();
  std::uint64_t cells = 0;
  for (std::size_t i = 0; i < xyz.size(); i += 3) {
    cells += traceSegment(grid, sensor, &xyz[i], [&](const Key& k) { passed.push_back(k); });
    Key k;
    ASSERT_TRUE(grid.pointToKey(xyz[i], xyz[i + 1], xyz[i + 2], k));
    hit.push_back(k);
  }
  const auto distinct = [](std::vector<Key>& keys) {
    const auto less = [](const Key& a, const Key& b) {
      return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    };
    std::sort(keys.begin(), keys.end(), less);
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  };
  distinct(passed), distinct(hit), distinct(got_passed), distinct(got_hit);
  std::vector<Key> missed;  // passed, and no endpoint
  for (const Key& k : passed)
    if (!std::binary_search(hit.begin(), hit.end(), k, [](const Key& a, const Key& b) {
          return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
        }))
      missed.push_back(k);
  EXPECT_EQ(stats.ray_cells, cells);
  EXPECT_TRUE(got_hit == hit) << got_hit.size() << " endpoints, expected " << hit.size();
  EXPECT_TRUE(got_passed == missed) << got_passed.size() << " cells passed, expected " << missed.size();
  EXPECT_GE(double(stats.skipped_cells), min_skipped * double(cells))
      << "the bundles passed " << stats.skipped_cells << " of " << cells << " cells";
}

}  // namespace

TEST(RayBundles, ADenseFramesCellsAreThoseOfItsPlainWalks) {
  // The frame's rays cross each cell near the sensor many times: most of their walks are bundled, and
  // the cells stay exactly the plain walk's. A sensor off the grid, and one on a cell corner, where a
  // power-of-two resolution makes the rays' crossings tie.
  const float off_grid[3] = {0.013f, -0.027f, 0.0049f}, corner[3] = {0.0f, 0.0f, 0.0f};
  expectPlainWalksUnion(depthFrame(off_grid, 160, 120), off_grid, 0.05, 1, 0.6);
  expectPlainWalksUnion(depthFrame(corner, 160, 120), corner, 0.0625, 2, 0.6);
}

TEST(RayBundles, RaysEveryWayAndOfEveryLengthKeepTheirCells) {
  // All six faces of the bundles' cube, each dense enough at 0.2 m to be swept, rays from one cell long to
  // far, a cluster of parallel rays.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), length(0.01f, 6.0f);
  const float sensor[3] = {0.31f, -0.77f, 1.05f};
  std::vector<float> xyz;
  for (int i = 0; i < 30000; ++i) {
    float d[3] = {unit(rng), unit(rng), unit(rng)};
    const float norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), t = length(rng);
    for (int a = 0; a < 3; ++a) xyz.push_back(sensor[a] + t * d[a] / norm);
  }
  for (int i = 0; i < 2000; ++i)
    for (float c : {sensor[0] + 4.0f, sensor[1] + 1e-5f * float(i % 40), sensor[2] + 1e-5f * float(i / 40)})
      xyz.push_back(c);
  expectPlainWalksUnion(xyz, sensor, 0.2, 2, 0.05);
}

TEST(ScanInsertion, BuffersKeptForTheThreadsNextScanCarryNothingOver) {
  // insertRays keeps its buffers for the calling thread's next scan, whatever map that goes into. Scans of
  // two maps of different grids, interleaved on one thread (a large scan, then one small enough that the
  // buffers are let go), give each map what scans on fresh threads give it.
  const float a[3] = {0.013f, -0.027f, 0.0049f}, b[3] = {0.41f, 0.12f, -0.23f};
  const std::vector<float> large = depthFrame(a, 400, 300), small = depthFrame(b, 80, 60);
  for (unsigned threads : {1u, 2u}) {
    const auto insert = [threads](FastOctTree& map, const float* sensor, const std::vector<float>& xyz) {
      ScanOptions options;
      options.threads = threads;
      insertRays(map, sensor, xyz.data(), xyz.size() / 3, 3 * sizeof(float), options);
    };
    const auto fresh = [&](FastOctTree& map, const float* sensor, const std::vector<float>& xyz) {
      std::thread([&] { insert(map, sensor, xyz); }).join();
    };
    FastOctTree fine(0.05), coarse(0.1), fine_fresh(0.05), coarse_fresh(0.1);
    for (FastOctTree* map : {&fine, &coarse, &fine_fresh, &coarse_fresh})
      map->setUpdateRule(UpdateRule::LogOdds);
    insert(fine, a, large), insert(coarse, b, small), insert(fine, b, small), insert(coarse, a, large);
    fresh(fine_fresh, a, large), fresh(fine_fresh, b, small), fresh(coarse_fresh, b, small);
    fresh(coarse_fresh, a, large);
    for (const auto& [kept, alone] : {std::pair<FastOctTree*, FastOctTree*>{&fine, &fine_fresh},
                                      std::pair<FastOctTree*, FastOctTree*>{&coarse, &coarse_fresh}}) {
      const FastOctTree::CanonicalPool pk = kept->canonicalPool(), pa = alone->canonicalPool();
      EXPECT_GT(kept->getUnsettledCount(), 0u);
      EXPECT_EQ(pk.words, pa.words) << threads << " threads";
      ASSERT_EQ(pk.values.size(), pa.values.size());
      EXPECT_EQ(std::memcmp(pk.values.data(), pa.values.data(), pk.values.size() * sizeof(float)), 0);
    }
  }
}

TEST(ScanInsertion, RaysBeyondTheWalkersReachStillFreeEveryCell) {
  // At 1 mm, rays of a kilometre pass more cells than the block walker's words span; they walk cell by
  // cell. The short ones walk in blocks. Together they must free exactly traceSegment's cells.
  const double res = 0.001;
  const float sensor[3] = {0.37f, -0.21f, 0.05f};
  const std::vector<std::array<float, 3>> ends = {
      {1200.0f, -0.3f, 0.2f}, {0.1f, 0.2f, -1100.0f}, {-3.0f, 2.0f, 1.0f}, {0.5f, 900.0f, 0.4f}};
  ASSERT_GT(1100.0 / res, double(detail::BlockRayWalker::kReach));
  ASSERT_LT(900.0 / res, double(detail::BlockRayWalker::kReach));
  Cloud cloud;
  std::vector<Key> expected_free, endpoints;
  std::uint64_t ray_cells = 0;
  for (const auto& e : ends) {
    cloud.push_back(pcl::PointXYZ(e[0], e[1], e[2]));
    const std::vector<Key> walk = ourRay(CellGrid(res), sensor, e.data());
    ray_cells += walk.size();
    expected_free.insert(expected_free.end(), walk.begin(), walk.end());
    Key k;
    ASSERT_TRUE(CellGrid(res).pointToKey(e[0], e[1], e[2], k));
    endpoints.push_back(k);
  }
  const auto less = [](const Key& a, const Key& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  };
  std::sort(expected_free.begin(), expected_free.end(), less);
  expected_free.erase(std::unique(expected_free.begin(), expected_free.end()), expected_free.end());
  for (bool line_burst : {true, false}) {
    FastOctTree tree(res);
    ScanOptions options;
    options.line_burst = line_burst;
    const ScanStats st = insertRays(tree, sensor, &cloud[0].x, cloud.size(), sizeof(pcl::PointXYZ), options);
    EXPECT_EQ(st.ray_cells, ray_cells);
    EXPECT_EQ(tree.getFreeCount(), expected_free.size());
    for (const Key& k : expected_free) ASSERT_EQ(tree.getCell(k), CellState::Free) << toString(k);
    EXPECT_EQ(tree.getOccupiedCount(), endpoints.size());
    for (const Key& k : endpoints) EXPECT_EQ(tree.getCell(k), CellState::Occupied) << toString(k);
  }
}

TEST_P(ScanInsertionOnScans, PoseFromTheCloudOrGivenExplicitly) {
  auto cloud = pcl_fot_test::loadScan("room_scan1.pcd");
  cloud->sensor_origin_ = Eigen::Vector4f(1.3f, -0.4f, 0.2f, 0.0f);
  cloud->sensor_orientation_ = Eigen::Quaternionf(Eigen::AngleAxisf(0.6931f, Eigen::Vector3f::UnitZ()));
  FastOctTree from_cloud(0.1), from_affine(0.1), from_matrix(0.1);
  insertScan(from_cloud, *cloud);
  const Eigen::Affine3f pose =
      Eigen::Translation3f(1.3f, -0.4f, 0.2f) * Eigen::AngleAxisf(0.6931f, Eigen::Vector3f::UnitZ());
  insertScan(from_affine, *cloud, pose);
  insertScan(from_matrix, *cloud, Eigen::Matrix4f(pose.matrix()));
  EXPECT_TRUE(from_cloud == from_affine);
  EXPECT_TRUE(from_cloud == from_matrix);
  // The sensor's own cell lies on every ray: it is free.
  EXPECT_EQ(from_cloud.getCellAtPoint(1.3, -0.4, 0.2), CellState::Free);
}

TEST(ScanInsertion, RangesNanAndPrecedence) {
  Cloud cloud;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.push_back(pcl::PointXYZ(5.05f, 0.05f, 0.05f));  // endpoint in cell (50, 0, 0) at 0.1 m
  cloud.push_back(pcl::PointXYZ(2.05f, 0.05f, 0.05f));  // endpoint on the first ray's path: occupied wins
  cloud.push_back(pcl::PointXYZ(nan, 1.0f, 1.0f));
  cloud.push_back(pcl::PointXYZ(0.0f, 30.05f, 0.05f));  // beyond max range: free up to 10 m only
  cloud.push_back(pcl::PointXYZ(0.02f, 0.01f, 0.0f));   // within min range: ignored
  FastOctTree tree(0.1);
  ScanOptions options;
  options.max_range = 10.0;
  options.min_range = 0.05;
  const ScanStats st = insertScan(tree, cloud, Eigen::Affine3f::Identity(), options);
  EXPECT_EQ(st.non_finite, 1u);
  EXPECT_EQ(st.too_close, 1u);
  EXPECT_EQ(st.truncated, 1u);
  EXPECT_EQ(st.rays, 3u);
  EXPECT_EQ(st.occupied, 2u);
  EXPECT_EQ(tree.getCell({50, 0, 0}), CellState::Occupied);
  EXPECT_EQ(tree.getCell({20, 0, 0}), CellState::Occupied) << "occupied wins over free within a scan";
  EXPECT_EQ(tree.getCell({49, 0, 0}), CellState::Free);
  EXPECT_EQ(tree.getCell({0, 98, 0}), CellState::Free);
  EXPECT_EQ(tree.getCell({0, 99, 0}), CellState::Unknown)
      << "the truncated ray ends at 10 m, end cell excluded";
  EXPECT_EQ(tree.getCell({0, 300, 0}), CellState::Unknown) << "and marks no endpoint";
  EXPECT_EQ(tree.getOccupiedCount(), 2u);

  // A later scan's ray through an occupied cell frees it.
  Cloud later;
  later.push_back(pcl::PointXYZ(3.05f, 0.05f, 0.05f));
  insertScan(tree, later, Eigen::Affine3f::Identity());
  EXPECT_EQ(tree.getCell({20, 0, 0}), CellState::Free);
  EXPECT_EQ(tree.getCell({30, 0, 0}), CellState::Occupied);
}

TEST(ScanInsertion, BadSensorPoseIsAnErrorAndChangesNothing) {
  Cloud cloud;
  cloud.push_back(pcl::PointXYZ(1, 1, 1));
  FastOctTree tree(0.1);
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.translation() << std::nanf(""), 0, 0;
  EXPECT_THROW(insertScan(tree, cloud, pose), std::invalid_argument);
  pose.translation() << 1e9f, 0, 0;
  EXPECT_THROW(insertScan(tree, cloud, pose), std::out_of_range);
  EXPECT_TRUE(tree.empty());
  EXPECT_EQ(insertScan(tree, Cloud(), Eigen::Affine3f::Identity()).rays, 0u) << "an empty cloud is fine";
}

TEST(CastRay, StopsAtTheFirstCellThatIsNotFree) {
  FastOctTree tree(1.0);
  for (int x = 0; x < 10; ++x) tree.setCell({x, 0, 0}, CellState::Free);
  tree.setCell({10, 0, 0}, CellState::Occupied);
  const float origin[3] = {0.5f, 0.5f, 0.5f}, along_x[3] = {1, 0, 0}, along_y[3] = {0, 2, 0};
  Key hit;
  EXPECT_TRUE(castRay(tree, origin, along_x, hit));
  EXPECT_EQ(hit, (Key{10, 0, 0}));
  EXPECT_FALSE(castRay(tree, origin, along_x, hit, 5.0)) << "beyond the maximum range";
  EXPECT_FALSE(castRay(tree, origin, along_y, hit));
  EXPECT_EQ(hit, (Key{0, 1, 0})) << "stops at the unknown cell";
  EXPECT_FALSE(castRay(tree, origin, along_y, hit, -1.0, true)) << "ignoring unknown cells it leaves the map";
  const float at_wall[3] = {10.5f, 0.5f, 0.5f};
  EXPECT_TRUE(castRay(tree, at_wall, along_x, hit));
  EXPECT_EQ(hit, (Key{10, 0, 0})) << "the origin's own cell counts";
  const float zero[3] = {0, 0, 0};
  EXPECT_THROW(castRay(tree, origin, zero, hit), std::invalid_argument);
  const float far_away[3] = {1e6f, 1e6f, 1e6f}, back[3] = {-1, -1, -1};
  EXPECT_FALSE(castRay(tree, far_away, back, hit, -1.0, true)) << "a ray that misses the map ends";
}

PCL_FOT_SCAN_TESTS(CastRayOnScans);

TEST_P(CastRayOnScans, SameAnswerOnTreeAndGridOverAScanMap) {
  const auto cloud = pcl_fot_test::loadScan("room_scan1.pcd");
  const CellGrid vg(0.05);
  FastOctTree tree(vg);
  FastOccMesh grid(vg, 1024);
  insertScan(tree, *cloud);
  insertScan(grid, *cloud);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const float origin[3] = {0.1f, 0.2f, 0.0f};
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const float dir[3] = {u(rng), u(rng), 0.3f * u(rng)};
    Key a, b;
    const bool ha = castRay(tree, origin, dir, a, 20.0, true), hb = castRay(grid, origin, dir, b, 20.0, true);
    ASSERT_EQ(ha, hb);
    if (ha) {
      ASSERT_EQ(a, b);
      ++hits;
    }
  }
  EXPECT_GT(hits, 1000) << "rays from inside the room mostly hit a wall";
}
