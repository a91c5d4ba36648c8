#pragma once

#include <string>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace fot_bench {

/** One real scan as the benchmarks use it: in a frame whose origin is the sensor (or the centre). */
struct BenchScan {
  std::string name;   ///< file name without extension
  double resolution;  ///< chosen so the scan fits the paper's 1024^3 grid
  bool has_sensor;    ///< false for airborne terrain: no ray origin
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud;
  std::size_t finite;  ///< points with finite coordinates
};

/**
 * Loads the scans of PCL's data repository listed in doc/benchmarks.md from data_dir. The terrain sample
 * is in UTM coordinates and is moved to its own centre, as a mapper would pick its map origin.
 */
std::vector<BenchScan> loadBenchScans(const std::string& data_dir);

/** The files loadBenchScans reads. */
std::vector<std::string> benchScanFiles(const std::string& data_dir);

/** The scan of that name; std::runtime_error if it was not loaded. */
const BenchScan& findScan(const std::vector<BenchScan>& scans, const std::string& name);

}  // namespace fot_bench
