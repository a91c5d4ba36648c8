// PCL's own algorithms, each given KdTree (FLANN), nanoflann and FastOctTreeSearch through setSearchMethod.
#include "sections.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>

#include <pcl/common/transforms.h>
#include <pcl/features/fpfh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/icp.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/region_growing.h>
#include <pcl/surface/mls.h>

#include <pcl_fot/pcl/search/fast_oct_tree_search.h>

#include "bench_util.h"
#include "nanoflann_search.h"

namespace fot_bench {
namespace {

using Point = pcl::PointXYZ;
using Cloud = pcl::PointCloud<Point>;
using KdTree = pcl::search::KdTree<Point>;
/** Makes the search an algorithm gets: KdTree or ours, new for every run, as a user's code would. */
using MakeSearch = std::function<KdTree::Ptr()>;

/** One algorithm: runs with the search it is given and returns its result as numbers to compare. */
struct Algorithm {
  std::string name, setting;
  bool labels;  // the numbers are each point's cluster, not values
  std::function<std::vector<double>(const MakeSearch&)> run;
};

/** Each point's cluster, named by its smallest index; -1 for a point in none. */
std::vector<double> clusterLabels(const std::vector<pcl::PointIndices>& clusters, std::size_t points) {
  std::vector<double> label(points, -1);
  for (const auto& c : clusters) {
    const double name = *std::min_element(c.indices.begin(), c.indices.end());
    for (const auto i : c.indices) label[std::size_t(i)] = name;
  }
  return label;
}

std::vector<double> matrixAsNumbers(const Eigen::Matrix4f& m) {
  return std::vector<double>(m.data(), m.data() + 16);
}

/** How far the two results lie apart: the points in another cluster, or the largest difference. */
std::string agreement(const Algorithm& a, const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size()) return format("%zu against %zu values", x.size(), y.size());
  std::size_t differ = 0;
  double largest = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (x[i] == y[i] || (std::isnan(x[i]) && std::isnan(y[i]))) continue;
    ++differ;
    largest = std::max(largest, std::abs(x[i] - y[i]));
  }
  if (differ == 0) return "identical";
  return a.labels ? format("%zu points in another cluster", differ)
                  : format("largest difference %.1e", largest);
}

std::vector<Algorithm> algorithms(const Cloud::Ptr& cloud, const pcl::PointCloud<pcl::Normal>::Ptr& normals,
                                  const Cloud::Ptr& moved, double res) {
  return {
      {"FPFHEstimation", format("radius %.2f m", 5 * res), false,
       [=](const MakeSearch& search) {
         pcl::FPFHEstimation<Point, pcl::Normal, pcl::FPFHSignature33> f;
         f.setInputCloud(cloud);
         f.setInputNormals(normals);
         f.setSearchMethod(search());
         f.setRadiusSearch(5 * res);
         pcl::PointCloud<pcl::FPFHSignature33> out;
         f.compute(out);
         std::vector<double> v;
         for (const auto& h : out) v.insert(v.end(), h.histogram, h.histogram + 33);
         return v;
       }},
      {"MovingLeastSquares", format("radius %.2f m, normals", 5 * res), false,
       [=](const MakeSearch& search) {
         pcl::MovingLeastSquares<Point, pcl::PointNormal> m;
         m.setInputCloud(cloud);
         m.setSearchMethod(search());
         m.setSearchRadius(5 * res);
         m.setComputeNormals(true);
         pcl::PointCloud<pcl::PointNormal> out;
         m.process(out);
         std::vector<double> v;
         // Points only: PCL 1.13 leaves some normals uninitialised (valgrind traces them to its MLSResult).
         for (const auto& p : out) v.insert(v.end(), {p.x, p.y, p.z});
         return v;
       }},
      {"RegionGrowing", "k = 30", true,
       [=](const MakeSearch& search) {
         pcl::RegionGrowing<Point, pcl::Normal> rg;
         rg.setInputCloud(cloud);
         rg.setInputNormals(normals);
         rg.setSearchMethod(search());
         rg.setNumberOfNeighbours(30);
         rg.setMinClusterSize(30);
         std::vector<pcl::PointIndices> out;
         rg.extract(out);
         return clusterLabels(out, cloud->size());
       }},
      {"EuclideanClusterExtraction", format("tolerance %.2f m", 2.5 * res), true,
       [=](const MakeSearch& search) {
         pcl::EuclideanClusterExtraction<Point> ec;
         ec.setInputCloud(cloud);
         ec.setSearchMethod(search());
         ec.setClusterTolerance(2.5 * res);
         ec.setMinClusterSize(20);
         std::vector<pcl::PointIndices> out;
         ec.extract(out);
         return clusterLabels(out, cloud->size());
       }},
      {"IterativeClosestPoint", format("target search, %.2f m correspondences", 10 * res), false,
       [=](const MakeSearch& search) {
         pcl::IterativeClosestPoint<Point, Point> icp;
         icp.setSearchMethodTarget(search());
         icp.setInputSource(moved);
         icp.setInputTarget(cloud);
         icp.setMaxCorrespondenceDistance(10 * res);
         icp.setMaximumIterations(50);
         Cloud aligned;
         icp.align(aligned);
         return matrixAsNumbers(icp.getFinalTransformation());
       }},
      {"GeneralizedIterativeClosestPoint", format("both searches, %.2f m correspondences", 10 * res), false,
       [=](const MakeSearch& search) {
         pcl::GeneralizedIterativeClosestPoint<Point, Point> gicp;
         gicp.setSearchMethodSource(search());
         gicp.setSearchMethodTarget(search());
         gicp.setInputSource(moved);
         gicp.setInputTarget(cloud);
         gicp.setMaxCorrespondenceDistance(10 * res);
         Cloud aligned;
         gicp.align(aligned);
         return matrixAsNumbers(gicp.getFinalTransformation());
       }},
  };
}

/** One scan, filtered to a voxel grid of `res`, through every algorithm. */
void benchScan(const BenchScan& scan, double res, int repeats, Table& table, std::vector<double>& ratios,
               std::vector<double>& nano_ratios) {
  Cloud::Ptr cloud(new Cloud), moved(new Cloud);
  pcl::VoxelGrid<Point> grid;
  grid.setInputCloud(scan.cloud);
  grid.setLeafSize(float(res), float(res), float(res));
  grid.filter(*cloud);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  pcl::NormalEstimation<Point, pcl::Normal> ne;
  ne.setInputCloud(cloud);
  ne.setRadiusSearch(3 * res);
  ne.compute(*normals);
  const Eigen::Affine3f motion = Eigen::Translation3f(float(2 * res), float(-res), float(0.5 * res)) *
                                 Eigen::AngleAxisf(0.03f, Eigen::Vector3f::UnitZ());
  pcl::transformPointCloud(*cloud, *moved, motion);

  const MakeSearch flann = [] { return KdTree::Ptr(new KdTree); };
  const MakeSearch ours = [] { return KdTree::Ptr(new pcl::fot::search::FastOctTreeSearch<Point>); };
  for (const Algorithm& a : algorithms(cloud, normals, moved, res)) {
    // As PCL 1.15's KdTreeNanoflann: leaves of 10 points where the algorithm asks 1-NN (ICP's
    // correspondences), of 20 where it asks k-NN or radius searches.
    const std::size_t leaf = a.name == "IterativeClosestPoint" ? 10 : 20;
    const MakeSearch nano = [leaf] { return KdTree::Ptr(new NanoflannKdTree<Point>(leaf)); };
    std::vector<double> t_flann, t_nano, t_ours, r_flann, r_nano, r_ours;
    for (int r = 0; r < repeats; ++r) {  // in turn, so that a change in the machine's load falls on all
      std::fprintf(stderr, "  PCL algorithms: %s, %s, round %d of %d\n", scan.name.c_str(), a.name.c_str(),
                   r + 1, repeats);
      t_flann.push_back(timeOnce([&] { r_flann = a.run(flann); }) * 1e3);
      t_nano.push_back(timeOnce([&] { r_nano = a.run(nano); }) * 1e3);
      t_ours.push_back(timeOnce([&] { r_ours = a.run(ours); }) * 1e3);
    }
    const double ratio = median(t_flann) / median(t_ours), nano_ratio = median(t_nano) / median(t_ours);
    ratios.push_back(ratio);
    nano_ratios.push_back(nano_ratio);
    table.add({scan.name, std::to_string(cloud->size()), a.name, a.setting, format("%.1f", median(t_flann)),
               format("%.1f", median(t_nano)), format("%.1f", median(t_ours)), format("**%.2f×**", ratio),
               format("**%.2f×**", nano_ratio), agreement(a, r_flann, r_ours),
               agreement(a, r_flann, r_nano)});
  }
}

}  // namespace

std::string benchPclAlgorithms(const std::vector<BenchScan>& scans, int repeats) {
  Table table({"scan", "points", "algorithm", "setting", "KdTree (FLANN) ms", "nanoflann ms",
               "FastOctTreeSearch ms", "KdTree / FOT", "nanoflann / FOT", "results (FLANN, FOT)",
               "results (FLANN, nanoflann)"});
  std::vector<double> ratios, nano_ratios;
  benchScan(findScan(scans, "room_scan1"), 0.05, repeats, table, ratios, nano_ratios);
  benchScan(findScan(scans, "kinect_capture0001"), 0.01, repeats, table, ratios, nano_ratios);
  const auto [lo, hi] = std::minmax_element(ratios.begin(), ratios.end());
  const auto [nano_lo, nano_hi] = std::minmax_element(nano_ratios.begin(), nano_ratios.end());
  return "## PCL's algorithms with FastOctTreeSearch\n\n" +
         format(
             "Each algorithm runs on a scan filtered by `pcl::VoxelGrid`, once with `pcl::search::KdTree` "
             "(FLANN), once with nanoflann behind the same interface, set up as PCL 1.15's `KdTreeNanoflann` "
             "(leaves of 10 points for ICP's 1-NN, 20 for the others; `tools/bench/nanoflann_search.h`), and "
             "once with `FastOctTreeSearch` made as a `KdTree` is (it picks its own cell edge), each handed "
             "over by `setSearchMethod` and built anew in each run, as a user's code would. "
             "Medians of %d rounds, the three in turn in each round. Normals for FPFH and region growing are "
             "computed once beforehand; ICP and GICP register the cloud moved by a small known motion back "
             "onto it. \"Results\" compares each search's output with FLANN's: each point's cluster, or "
             "every number they hold (for MovingLeastSquares the points, not the normals, some of which PCL "
             "1.13 leaves uninitialised). Where FLANN's and ours differ, the searches found the same "
             "neighbour distances, but neighbours at exactly equal distance came in another order (FLANN's "
             "traversal, against the index order here), so sums rounded apart, or a k-th and (k+1)-th "
             "neighbour tied and each kept another (the test "
             "`SearchDropIn.NormalEstimationGivesTheSameNormals` checks the distances point by point).\n\n",
             repeats) +
         table.markdown() + "\n" +
         format(
             "Summary: KdTree's time over FastOctTreeSearch's is %.2f× to %.2f×; nanoflann's %.2f× to "
             "%.2f×.\n",
             *lo, *hi, *nano_lo, *nano_hi);
}

}  // namespace fot_bench
