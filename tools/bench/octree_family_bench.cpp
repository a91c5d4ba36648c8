// The pcl::octree look-alikes against pcl::octree: each search, a leaf walk, the centroids, the density and
// adjacency octrees and the change detector, build plus queries.
#include "sections.h"

#include <cstdio>
#include <functional>
#include <random>
#include <type_traits>

#include <pcl/common/point_tests.h>
#include <pcl/octree/octree_pointcloud_adjacency.h>
#include <pcl/octree/octree_pointcloud_changedetector.h>
#include <pcl/octree/octree_pointcloud_density.h>
#include <pcl/octree/octree_pointcloud_voxelcentroid.h>
#include <pcl/octree/octree_search.h>

#include <pcl_fot/pcl/octree/octree_point_cloud_adjacency.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_change_detector.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_density.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_search.h>
#include <pcl_fot/pcl/octree/octree_point_cloud_voxel_centroid.h>

#include "bench_util.h"

namespace fot_bench {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

/** One search, run by both octrees: it builds from the target, runs its queries and returns a checksum. */
struct Row {
  std::string name;
  std::size_t queries;
  std::function<double(bool ours)> run;
};

/** Every n-th finite point of the cloud, jittered by up to one cell. */
std::vector<pcl::PointXYZ> queriesFrom(const Cloud& cloud, std::size_t count, double res) {
  std::vector<pcl::PointXYZ> finite;
  for (const auto& p : cloud)
    if (pcl::isFinite(p)) finite.push_back(p);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-float(res), float(res));
  std::vector<pcl::PointXYZ> queries;
  const std::size_t step = std::max<std::size_t>(1, finite.size() / count);
  for (std::size_t i = 0; i < finite.size() && queries.size() < count; i += step)
    queries.emplace_back(finite[i].x + jitter(rng), finite[i].y + jitter(rng), finite[i].z + jitter(rng));
  return queries;
}

/** Builds the octree (PCL's or ours) of the cloud, then runs `query` on it, all timed together. */
template <template <typename...> class Octree, typename Query>
double buildAndQuery(const Cloud::Ptr& cloud, double res, Query&& query) {
  Octree<pcl::PointXYZ> octree(res);
  octree.setInputCloud(cloud);
  octree.addPointsFromInputCloud();
  return query(octree);
}

/** buildAndQuery in a bounding box defined first, as a user who knows the workspace defines it. */
template <template <typename...> class Octree, typename Query>
double buildInBoxAndQuery(const Cloud::Ptr& cloud, double res, const double lo[3], const double hi[3],
                          Query&& query) {
  Octree<pcl::PointXYZ> octree(res);
  octree.defineBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  octree.setInputCloud(cloud);
  octree.addPointsFromInputCloud();
  return query(octree);
}

/**
 * Adds the points one at a time to an empty octree (addPointToCloud), each followed by a search for the
 * next point: nearestKSearch with k = 1, or approxNearestSearch. Returns the sum of the distances.
 */
template <template <typename...> class Octree>
double addAndSearch(const std::vector<pcl::PointXYZ>& points, double res, bool approx) {
  Octree<pcl::PointXYZ> octree(res);
  Cloud::Ptr cloud(new Cloud);
  octree.setInputCloud(cloud);
  pcl::Indices idx;
  std::vector<float> dist;
  double s = 0;
  for (std::size_t i = 0; i + 1 < points.size(); ++i) {
    octree.addPointToCloud(points[i], cloud);
    if (approx) {
      pcl::index_t index;
      float d;
      octree.approxNearestSearch(points[i + 1], index, d);
      s += d;
    } else {
      octree.nearestKSearch(points[i + 1], 1, idx, dist);
      s += dist[0];
    }
  }
  return s;
}

std::string scanTable(const BenchScan& target, const BenchScan& source, int repeats,
                      std::vector<std::string>& verdicts) {
  const double res = target.resolution;
  const Cloud::Ptr cloud = target.cloud;
  // Queries inside the target's box: PCL asserts on a voxel search outside it.
  double lo[3], hi[3];
  {
    pcl::octree::OctreePointCloudSearch<pcl::PointXYZ> box(res);
    box.setInputCloud(cloud);
    box.addPointsFromInputCloud();
    box.getBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  }
  Cloud inside;
  for (const auto& p : *source.cloud)
    if (p.x > lo[0] + res && p.y > lo[1] + res && p.z > lo[2] + res && p.x < hi[0] - res &&
        p.y < hi[1] - res && p.z < hi[2] - res)
      inside.push_back(p);
  const auto near = queriesFrom(inside, 20000, res);
  const auto few = queriesFrom(inside, 2000, res);
  pcl::Indices idx;
  std::vector<float> dist;
  // Each query adds its answer to a checksum: the sizes, the indices and the distances.
  const auto sum = [&](double& s) {
    for (std::size_t i = 0; i < idx.size(); ++i) s += double(idx[i]) * 1e-6 * double(i + 1);
    for (const float d : dist) s += d;
    s += double(idx.size());
  };
  const auto search = [&](bool ours, auto&& body) {
    return ours ? buildAndQuery<pcl::fot::OctreePointCloudSearch>(cloud, res, body)
                : buildAndQuery<pcl::octree::OctreePointCloudSearch>(cloud, res, body);
  };
  const Eigen::Vector3f half = Eigen::Vector3f::Constant(float(4 * res));
  // A loop that grows the octree point by point and searches after each point, as an odometry front end does.
  const auto growing = queriesFrom(*cloud, 4000, 0.0);
  std::vector<Row> rows = {
      {"build only", 0,
       [&](bool ours) { return search(ours, [&](auto& t) { return double(t.getLeafCount()); }); }},
      {"voxelSearch", near.size(),
       [&](bool ours) {
         return search(ours, [&](auto& t) {
           double s = 0;
           for (const auto& q : near) {
             idx.clear();
             dist.clear();
             t.voxelSearch(q, idx);
             sum(s);
           }
           return s;
         });
       }},
      {"nearestKSearch k = 1", near.size(),
       [&](bool ours) {
         return search(ours, [&](auto& t) {
           double s = 0;
           for (const auto& q : near) {
             t.nearestKSearch(q, 1, idx, dist);
             s += dist[0];  // the index is left out: ties may go to either point
           }
           return s;
         });
       }},
      {"nearestKSearch k = 10", near.size(),
       [&](bool ours) {
         return search(ours, [&](auto& t) {
           double s = 0;
           for (const auto& q : near) {
             t.nearestKSearch(q, 10, idx, dist);
             for (const float d : dist) s += d;
           }
           return s;
         });
       }},
      {"approxNearestSearch", near.size(),
       [&](bool ours) {
         return search(ours, [&](auto& t) {
           double s = 0;
           for (const auto& q : near) {
             pcl::index_t i = 0;
             float d = 0;
             t.approxNearestSearch(q, i, d);
             s += d + 1e-6 * double(i);
           }
           return s;
         });
       }},
      {"radiusSearch r = 3 cells", few.size(),
       [&](bool ours) {
         return search(ours, [&](auto& t) {
           double s = 0;
           for (const auto& q : few) {
             t.radiusSearch(q, 3 * res, idx, dist);
             sum(s);
           }
           return s;
         });
       }},
      {"radiusSearch r = 3 cells, max_nn 10", few.size(),
       [&](bool ours) {
         return search(ours, [&](auto& t) {
           double s = 0;
           for (const auto& q : few) {
             t.radiusSearch(q, 3 * res, idx, dist, 10);
             sum(s);
           }
           return s;
         });
       }},
      {"boxSearch 8 cells wide", few.size(),
       [&](bool ours) {
         return search(ours, [&](auto& t) {
           double s = 0;
           for (const auto& q : few) {
             dist.clear();
             t.boxSearch(q.getVector3fMap() - half, q.getVector3fMap() + half, idx);
             sum(s);
           }
           return s;
         });
       }},
      {"getIntersectedVoxelIndices", few.size(),
       [&](bool ours) {
         return search(ours, [&](auto& t) {
           double s = 0;
           const Eigen::Vector3f origin = Eigen::Vector3f::Zero();
           for (const auto& q : few) {
             dist.clear();
             t.getIntersectedVoxelIndices(origin, q.getVector3fMap() - origin, idx, 1);
             sum(s);
           }
           return s;
         });
       }},
      {"getIntersectedVoxelIndices in a box 64× the cloud's, from its edge", few.size(),
       [&](bool ours) {
         // The cloud's box grown 64 times around its centre; rays from near the big box's corner.
         double big_lo[3], big_hi[3];
         Eigen::Vector3f origin;
         for (int a = 0; a < 3; ++a) {
           const double centre = 0.5 * (lo[a] + hi[a]), half = 32.0 * (hi[a] - lo[a]);
           big_lo[a] = centre - half;
           big_hi[a] = centre + half;
           origin[a] = float(centre - 0.9 * half);
         }
         const auto rays = [&](auto& t) {
           double s = 0;
           for (const auto& q : few) {
             dist.clear();
             t.getIntersectedVoxelIndices(origin, q.getVector3fMap() - origin, idx, 1);
             sum(s);
           }
           return s;
         };
         return ours ? buildInBoxAndQuery<pcl::fot::OctreePointCloudSearch>(cloud, res, big_lo, big_hi, rays)
                     : buildInBoxAndQuery<pcl::octree::OctreePointCloudSearch>(cloud, res, big_lo, big_hi,
                                                                               rays);
       }},
      {format("add a point, then nearestKSearch k = 1 (%zu times)", growing.size()), growing.size(),
       [&](bool ours) {
         return ours ? addAndSearch<pcl::fot::OctreePointCloudSearch>(growing, res, false)
                     : addAndSearch<pcl::octree::OctreePointCloudSearch>(growing, res, false);
       }},
      {format("add a point, then approxNearestSearch (%zu times)", growing.size()), growing.size(),
       [&](bool ours) {
         return ours ? addAndSearch<pcl::fot::OctreePointCloudSearch>(growing, res, true)
                     : addAndSearch<pcl::octree::OctreePointCloudSearch>(growing, res, true);
       }},
      {"leaf walk: each leaf's point indices (leaf_depth_begin)", 1,
       [&](bool ours) {
         return search(ours, [&](auto& t) {
           double s = 0;
           for (auto it = t.leaf_depth_begin(); it != t.leaf_depth_end(); ++it) {
             idx.clear();
             dist.clear();
             it.getLeafContainer().getPointIndices(idx);
             sum(s);
           }
           return s;
         });
       }},
      {"getVoxelCentroids (voxel centroid octree)", 1,
       [&](bool ours) {
         const auto centroids = [&](auto& octree) {
           typename std::remove_reference_t<decltype(octree)>::AlignedPointTVector points;
           octree.getVoxelCentroids(points);
           double s = 0;
           for (const auto& p : points) s += double(p.x) + double(p.y) * 1e-3 + double(p.z) * 1e-6;
           return s;
         };
         return ours ? buildAndQuery<pcl::fot::OctreePointCloudVoxelCentroid>(cloud, res, centroids)
                     : buildAndQuery<pcl::octree::OctreePointCloudVoxelCentroid>(cloud, res, centroids);
       }},
      {"getVoxelDensityAtPoint (density octree)", near.size(),
       [&](bool ours) {
         const auto density = [&](auto& octree) {
           double s = 0;
           for (const auto& q : near) s += double(octree.getVoxelDensityAtPoint(q));
           return s;
         };
         return ours ? buildAndQuery<pcl::fot::OctreePointCloudDensity>(cloud, res, density)
                     : buildAndQuery<pcl::octree::OctreePointCloudDensity>(cloud, res, density);
       }},
      {"adjacency octree: each voxel's neighbours and points", 1,
       [&](bool ours) {
         const auto neighbours = [&](auto& octree) {
           double s = 0, i = 0;
           for (auto it = octree.begin(); it != octree.end(); ++it, ++i)
             s += double((*it)->size()) * (1.0 + i * 1e-9) + double((*it)->getPointCounter()) * 1e-3;
           return s;
         };
         return ours ? buildAndQuery<pcl::fot::OctreePointCloudAdjacency>(cloud, res, neighbours)
                     : buildAndQuery<pcl::octree::OctreePointCloudAdjacency>(cloud, res, neighbours);
       }},
      {"change detector: both buffers + new voxels", 1,
       [&](bool ours) {
         const auto detect = [&](auto& octree) {
           octree.setInputCloud(cloud);
           octree.addPointsFromInputCloud();
           octree.switchBuffers();
           octree.setInputCloud(source.cloud);
           octree.addPointsFromInputCloud();
           idx.clear();
           dist.clear();
           octree.getPointIndicesFromNewVoxels(idx);
           double s = 0;
           sum(s);
           return s;
         };
         if (ours) {
           pcl::fot::OctreePointCloudChangeDetector<pcl::PointXYZ> octree(res);
           return detect(octree);
         }
         pcl::octree::OctreePointCloudChangeDetector<pcl::PointXYZ> octree(res);
         return detect(octree);
       }},
  };

  Table t({"operation", "queries", "pcl::octree ms", "pcl::fot ms", "speed-up", "same answers"});
  std::size_t met = 0;
  double worst = 1e300;
  std::string worst_row;
  for (Row& row : rows) {
    std::vector<double> pcl_ms, fot_ms;
    double pcl_sum = 0, fot_sum = 0;
    for (int r = 0; r < repeats; ++r) {
      std::fprintf(stderr, "  octree: %s, %s, round %d of %d\n", target.name.c_str(), row.name.c_str(), r + 1,
                   repeats);
      scrubCaches();
      pcl_ms.push_back(timeOnce([&] { pcl_sum = row.run(false); }) * 1e3);
      scrubCaches();
      fot_ms.push_back(timeOnce([&] { fot_sum = row.run(true); }) * 1e3);
    }
    const double speedup = median(pcl_ms) / median(fot_ms);
    met += speedup >= 3.0;
    if (speedup < worst) {
      worst = speedup;
      worst_row = row.name;
    }
    t.add({row.name, row.queries ? format("%zu", row.queries) : "-", format("%.1f", median(pcl_ms)),
           format("%.1f", median(fot_ms)), format("%.2f×", speedup), pcl_sum == fot_sum ? "yes" : "**no**"});
  }
  verdicts.push_back(format("%s: %zu of %zu rows at least 3× pcl::octree; the slowest, %s, %.2f×.",
                            target.name.c_str(), met, rows.size(), worst_row.c_str(), worst));
  return format("**%s** (target), queries from %s, cells of %.2f m:\n\n", target.name.c_str(),
                source.name.c_str(), res) +
         t.markdown() + "\n";
}

}  // namespace

std::string benchOctreeFamily(const std::vector<BenchScan>& scans, int repeats) {
  std::string out =
      "## The pcl::octree look-alikes\n\n"
      "`pcl::fot::OctreePointCloudSearch`, the voxel centroid, density and adjacency octrees and "
      "`OctreePointCloudChangeDetector` against pcl::octree's, "
      "side by side in one run: each row times building the octree from the target scan and then its "
      "queries (points of the other scan, jittered by up to a cell), median of the rounds. \"Same answers\" "
      "compares a checksum of every answer: sizes, indices in order, distances (for k-NN the distances "
      "only, as tied points may come in either order). Goal: 3× pcl::octree on every row.\n\n";
  std::vector<std::string> verdicts;
  out += scanTable(findScan(scans, "kinect_capture0001"), findScan(scans, "kinect_capture0002"), repeats,
                   verdicts);
  out += scanTable(findScan(scans, "room_scan1"), findScan(scans, "room_scan2"), repeats, verdicts);
  out += scanTable(findScan(scans, "terrain_samp11"), findScan(scans, "terrain_samp11"), repeats, verdicts);
  for (const auto& v : verdicts) out += "- " + v + "\n";
  return out;
}

}  // namespace fot_bench
