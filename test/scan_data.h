#pragma once

#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include "synthetic_scene.h"

namespace pcl_fot_test {

/** The real scans: PCL_FOT_DATA_DIR from the environment, else the directory CMake found. */
inline std::string dataFile(const std::string& name) {
  const char* env = std::getenv("PCL_FOT_DATA_DIR");
  const std::string dir = (env && *env) ? env : PCL_FOT_DATA_DIR;
  return dir + "/" + name;
}

inline const std::vector<std::string>& allScans() {
  static const std::vector<std::string> names = {"kinect_capture0001.pcd", "kinect_capture0002.pcd",
                                                 "kinect_capture0003.pcd", "room_scan1.pcd",
                                                 "room_scan2.pcd",         "terrain_samp11.pcd"};
  return names;
}

/**
 * Which scans loadScan gives: the project's synthetic twins (always there), or PCL's real scans. A test
 * that reads scans runs on both (PCL_FOT_SCAN_TESTS); the real ones are skipped where the data is missing.
 */
enum class ScanSet { Synthetic, Real };

inline void PrintTo(ScanSet set, std::ostream* os) {
  *os << (set == ScanSet::Real ? "PCL's real scans" : "the synthetic twins");
}

inline ScanSet& currentScanSet() {
  static ScanSet set = ScanSet::Synthetic;
  return set;
}

inline bool realScansFound() {
  for (const std::string& name : allScans())
    if (!std::ifstream(dataFile(name))) return false;
  return true;
}

inline std::string missingScansMessage() {
  return "the real scans are not in '" + dataFile("") +
         "': get them from PCL's data repository (doc/user_guide.md lists the files) and set "
         "PCL_FOT_DATA_DIR";
}

/**
 * The scan `name` of the current set: the real file, or its synthetic twin of the same kind. Only tests
 * that run on both sets may read scans (PCL_FOT_SCAN_TESTS, or a value-parameterised test calling useScans).
 */
inline pcl::PointCloud<pcl::PointXYZ>::Ptr loadScan(const std::string& name) {
  const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
  if (!test || !test->value_param())
    throw std::logic_error("loadScan outside a test on both scan sets (PCL_FOT_SCAN_TESTS)");
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  if (currentScanSet() == ScanSet::Synthetic) {
    static std::mutex mutex;
    static std::map<std::string, pcl::PointCloud<pcl::PointXYZ>::ConstPtr> made;
    const std::lock_guard<std::mutex> lock(mutex);
    auto& twin = made[name];
    if (!twin) twin = fot_tools::syntheticTwin(name);
    *cloud = *twin;
    return cloud;
  }
  const std::string path = dataFile(name);
  if (pcl::io::loadPCDFile(path, *cloud) != 0 || cloud->empty())
    throw std::runtime_error("cannot read the real scan " + path + "; " + missingScansMessage());
  return cloud;
}

/** Makes `set` current; false where it is the real scans and they are missing (the test then skips). */
inline bool useScans(ScanSet set) {
  currentScanSet() = set;
  return set == ScanSet::Synthetic || realScansFound();
}

/** One value per scan set, made by `make` at its first use: an expensive map of a scan, shared by tests. */
template <typename T, typename Make>
const T& perScanSet(Make make) {
  static std::mutex mutex;
  static std::map<ScanSet, T> made;
  const std::lock_guard<std::mutex> lock(mutex);
  auto it = made.find(currentScanSet());
  if (it == made.end()) it = made.emplace(currentScanSet(), make()).first;
  return it->second;
}

/** Tests on scans: each runs on the synthetic twins, and on the real scans where they are found. */
class ScanTest : public ::testing::TestWithParam<ScanSet> {
 protected:
  void SetUp() override {
    if (!useScans(GetParam())) GTEST_SKIP() << missingScansMessage();
  }
};

/** n points drawn uniformly from the cube [0, side)³, from rng. */
inline pcl::PointCloud<pcl::PointXYZ>::Ptr randomCloud(std::mt19937& rng, std::size_t n, float side) {
  std::uniform_real_distribution<float> u(0.0f, side);
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (std::size_t i = 0; i < n; ++i) cloud->emplace_back(u(rng), u(rng), u(rng));
  return cloud;
}

inline pcl::PointCloud<pcl::PointXYZ>::Ptr randomCloud(std::size_t n, float side, unsigned seed) {
  std::mt19937 rng(seed);
  return randomCloud(rng, n, side);
}

/** Fills a pcl::octree and its look-alike alike from `cloud`, with dynamic depth if max_per_leaf is not 0. */
template <typename Reference, typename Ours>
void fillBoth(Reference& ref, Ours& ours, const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud,
              std::size_t max_per_leaf = 0) {
  ref.setInputCloud(cloud);
  ours.setInputCloud(cloud);
  if (max_per_leaf) {
    ref.enableDynamicDepth(max_per_leaf);
    ours.enableDynamicDepth(max_per_leaf);
  }
  ref.addPointsFromInputCloud();
  ours.addPointsFromInputCloud();
}

}  // namespace pcl_fot_test

/**
 * Declares the fixture `Suite` for TEST_P tests on scans and runs them on both sets:
 * "Synthetic/Suite.Name/scans" and "Real/Suite.Name/scans".
 */
#define PCL_FOT_SCAN_TESTS(Suite)                                                                   \
  class Suite : public ::pcl_fot_test::ScanTest {};                                                 \
  INSTANTIATE_TEST_SUITE_P(Synthetic, Suite, ::testing::Values(::pcl_fot_test::ScanSet::Synthetic), \
                           [](const auto&) { return std::string("scans"); });                       \
  INSTANTIATE_TEST_SUITE_P(Real, Suite, ::testing::Values(::pcl_fot_test::ScanSet::Real),           \
                           [](const auto&) { return std::string("scans"); })
