#pragma once

#include <string>
#include <vector>

#include "bench_scans.h"

namespace fot_bench {

/** Each section runs its experiment side by side in one process and returns Markdown. */
std::string benchCellAccess(const std::vector<BenchScan>& scans, int repeats);
std::string benchRayTracing(const std::vector<BenchScan>& scans, int repeats);
std::string benchSearch(const std::vector<BenchScan>& scans, int repeats);
/** FastOctTreeSearch against nanoflann as PCL 1.15 sets it up; the sliding-window map (reads the raw
 * terrain). */
std::string benchSearchAgainstNanoflann(const std::vector<BenchScan>& scans, const std::string& data_dir,
                                        int repeats);
/** pcl::fot's OctreePointCloudSearch and OctreePointCloudChangeDetector next to pcl::octree's. */
std::string benchOctreeFamily(const std::vector<BenchScan>& scans, int repeats);
/** PCL's features, surface, segmentation and registration algorithms with KdTree and with FastOctTreeSearch.
 */
std::string benchPclAlgorithms(const std::vector<BenchScan>& scans, int repeats);
/** Sequences of scans by the log-odds and binary rules, next to OctoMap's insertPointCloud. */
std::string benchMultiScan(const std::vector<BenchScan>& scans, int repeats);
/** Also plots Fig. 5 into plot_file (PNG, with gnuplot), which the Markdown links by its file name. */
std::string benchPsi(const std::vector<BenchScan>& scans, int repeats, int dmap_repeats,
                     const std::string& plot_file);

}  // namespace fot_bench
