// OctoMap's full .ot files, read without the library and checked through the OctoMap library itself.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <sstream>

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>

#include <pcl_fot/io/octomap.h>

#include "octomap_checks.h"
#include "scan_data.h"

using namespace pcl::fot;

namespace {

/** room_scan1 ray-traced into an OctoMap tree: log-odds of every kind, from many updates. */
template <typename OctoMapTree>
void mapRoom(OctoMapTree& om) {
  const auto& cloud = pcl_fot_test::perScanSet<pcl::PointCloud<pcl::PointXYZ>::Ptr>(
      [] { return pcl_fot_test::loadScan("room_scan1.pcd"); });
  octomap::Pointcloud scan;
  for (const auto& p : *cloud) scan.push_back(p.x, p.y, p.z);
  om.insertPointCloud(scan, octomap::point3d(0, 0, 0));
  om.insertPointCloud(scan, octomap::point3d(0.3f, 0.1f, 0));
}

template <typename OctoMapTree>
std::string ot(const OctoMapTree& om) {
  std::ostringstream out;
  EXPECT_TRUE(om.write(out));
  return out.str();
}

}  // namespace

PCL_FOT_SCAN_TESTS(OctoMapOt);

TEST_P(OctoMapOt, EveryLeafIsOctoMapsState) {
  octomap::OcTree om(0.05);
  mapRoom(om);
  const std::string bytes = ot(om);
  const FastOctTree ours = io::decodeOt(bytes.data(), bytes.size(), "room.ot");
  ASSERT_GT(ours.getOccupiedCount(), 1000u);
  ASSERT_GT(ours.getFreeCount(), 100000u);
  expectSameCells(om, ours);
  // The same cells as OctoMap's own maximum-likelihood .bt of the tree.
  std::ostringstream bt;
  ASSERT_TRUE(om.writeBinaryConst(bt));
  FastOctTree settled = ours;
  settled.toMaxLikelihood();
  EXPECT_TRUE(io::decodeBt(bt.str().data(), bt.str().size()) == settled);
  // On a grid whose origin is a whole number of cells away.
  io::OctoMapImportOptions shifted;
  shifted.origin[1] = -0.35;
  expectSameCells(om, io::decodeOt(bytes.data(), bytes.size(), "room.ot", shifted));
}

TEST_P(OctoMapOt, ColourAndStampedTrees) {
  octomap::ColorOcTree color(0.1);
  mapRoom(color);
  color.updateNode(octomap::point3d(1, 1, 1), true)->setColor(10, 20, 30);
  const std::string c = ot(color);
  expectSameCells(color, io::decodeOt(c.data(), c.size(), "color.ot"));
  octomap::OcTreeStamped stamped(0.1);
  mapRoom(stamped);
  const std::string s = ot(stamped);
  expectSameCells(stamped, io::decodeOt(s.data(), s.size(), "stamped.ot"));
}

TEST_P(OctoMapOt, EmptyTreesAndWhatCannotBeRead) {
  const octomap::OcTree empty(0.1);
  const std::string e = ot(empty);
  EXPECT_TRUE(io::decodeOt(e.data(), e.size()).empty());

  octomap::OcTree om(0.2);
  mapRoom(om);
  const std::string good = ot(om);
  auto refused = [](std::string bytes, const char* what) {
    try {
      io::decodeOt(bytes.data(), bytes.size(), "bad.ot");
    } catch (const io::FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "accepted a file with " << what;
  };
  std::string counting = good;
  counting.replace(counting.find("id OcTree"), 9, "id CountingOcTree");
  refused(counting, "knows OcTree, OcTreeStamped and ColorOcTree");
  std::string nan = good;
  // The first leaf: the root's descendants are written first-child first, so follow masks down.
  std::size_t at = nan.find("data\n") + 5;
  while (static_cast<unsigned char>(nan[at + 4]) != 0) at += 5;
  const float not_a_number = std::nanf("");
  std::memcpy(&nan[at], &not_a_number, 4);
  refused(nan, "log-odds is not finite");
  refused(good.substr(0, good.size() - 3), "truncated");
  refused(good + "xyz", "bytes follow the tree");
  std::string bigger = good;
  bigger.replace(bigger.find("size "), 5, "size 1");
  refused(bigger, "size");
  refused("# Octomap OcTree binary file\nid OcTree\nsize 0\nres 0.1\ndata\n", "does not start with");
}

TEST_P(OctoMapOt, DamagedFilesFailCleanlyOrLoadValidMaps) {
  octomap::OcTree om(0.2);
  mapRoom(om);
  const std::string good = ot(om);
  const std::size_t body = good.find("data\n") + 5;
  io::OctoMapImportOptions capped;
  capped.max_pool_bytes = 8 << 20;  // a flipped bit can turn a deep leaf into a huge cube
  std::mt19937 rng(2);
  int refused = 0, loaded = 0;
  auto attempt = [&](const std::string& bytes) {
    (loadsAValidMap(
         [&](const std::string& b) { return io::decodeOt(b.data(), b.size(), "damaged.ot", capped); }, bytes)
         ? loaded
         : refused)++;
  };
  for (int i = 0; i < 300; ++i) attempt(good.substr(0, rng() % good.size()));
  for (int i = 0; i < 500; ++i) {
    std::string b = good;
    b[body + rng() % (b.size() - body)] ^= char(1u << (rng() % 8));
    attempt(b);
  }
  EXPECT_EQ(refused + loaded, 800);
  EXPECT_GT(refused, 300);
}
