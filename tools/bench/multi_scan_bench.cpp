// Multi-scan mapping: the log-odds rule and the binary rule next to OctoMap's insertPointCloud.
#include <cmath>
#include <string>
#include <vector>

#include <octomap/OcTree.h>
#include <Eigen/Geometry>

#include <pcl_fot/mapping/scan_insertion.h>
#include <pcl_fot/tree/fast_oct_tree.h>

#include "bench_util.h"
#include "sections.h"
#include "synthetic_scene.h"

namespace fot_bench {
namespace {

struct Scan {
  std::vector<float> xyz;  // map frame, NaN points kept
  octomap::Pointcloud finite;
  float sensor[3];
};

struct Sequence {
  std::string name;
  double resolution;
  std::vector<Scan> scans;
};

Scan placed(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Affine3f& pose) {
  Scan s;
  for (const auto& p : cloud) {
    const Eigen::Vector3f q = pose * p.getVector3fMap();
    s.xyz.insert(s.xyz.end(), {q.x(), q.y(), q.z()});
    if (std::isfinite(q.x()) && std::isfinite(q.y()) && std::isfinite(q.z()))
      s.finite.push_back(q.x(), q.y(), q.z());
  }
  const Eigen::Vector3f t = pose.translation();
  s.sensor[0] = t.x(), s.sensor[1] = t.y(), s.sensor[2] = t.z();
  return s;
}

/** The sequences of the log-odds tests (test/test_log_odds_mapping.cpp). */
std::vector<Sequence> sequences(const std::vector<BenchScan>& scans) {
  const Eigen::Affine3f identity = Eigen::Affine3f::Identity();
  std::vector<Sequence> out;
  const Eigen::Affine3f ndt_guess =
      Eigen::Translation3f(1.79387f, 0.720047f, 0.0f) * Eigen::AngleAxisf(0.6931f, Eigen::Vector3f::UnitZ());
  out.push_back({"room pair, NDT guess, 5 cm",
                 0.05,
                 {placed(*findScan(scans, "room_scan1").cloud, identity),
                  placed(*findScan(scans, "room_scan2").cloud, ndt_guess)}});
  Sequence kinect{"three Kinect frames, 2 cm", 0.02, {}};
  for (const char* name : {"kinect_capture0001", "kinect_capture0002", "kinect_capture0003"})
    kinect.scans.push_back(placed(*findScan(scans, name).cloud, identity));
  out.push_back(kinect);
  Sequence room{"synthetic room, 6 poses, 5 cm", 0.05, {}};
  for (const auto& cloud : fot_tools::scanSyntheticRoom())
    room.scans.push_back(placed(*cloud, Eigen::Translation3f(cloud->sensor_origin_.head<3>()) *
                                            cloud->sensor_orientation_.normalized()));
  out.push_back(room);
  out.push_back({"room_scan1 seven times, 5 cm", 0.05,
                 std::vector<Scan>(7, placed(*findScan(scans, "room_scan1").cloud, identity))});
  return out;
}

}  // namespace

std::string benchMultiScan(const std::vector<BenchScan>& scans, int repeats) {
  Table table({"sequence", "scans", "OctoMap ms", "log-odds ms", "speed-up", "binary ms", "OctoMap bytes",
               "log-odds bytes", "memory ratio", "unsettled cells"});
  for (const Sequence& seq : sequences(scans)) {
    std::vector<double> t_octomap, t_ours, t_binary;
    std::size_t octomap_bytes = 0, our_bytes = 0;
    std::uint64_t unsettled = 0;
    for (int r = 0; r < repeats; ++r) {
      octomap::OcTree om(seq.resolution);
      t_octomap.push_back(timeOnce([&] {
        for (const Scan& s : seq.scans)
          om.insertPointCloud(s.finite, octomap::point3d(s.sensor[0], s.sensor[1], s.sensor[2]));
      }));
      octomap_bytes = om.memoryUsage();
      for (pcl::fot::UpdateRule rule : {pcl::fot::UpdateRule::LogOdds, pcl::fot::UpdateRule::Binary}) {
        pcl::fot::FastOctTree tree(seq.resolution);
        tree.setUpdateRule(rule);
        const double t = timeOnce([&] {
          for (const Scan& s : seq.scans)
            pcl::fot::insertRays(tree, s.sensor, s.xyz.data(), s.xyz.size() / 3, 3 * sizeof(float));
        });
        if (rule == pcl::fot::UpdateRule::Binary) {
          t_binary.push_back(t);
          continue;
        }
        t_ours.push_back(t);
        tree.shrinkToFit();
        our_bytes = tree.getMemoryBytes();
        unsettled = tree.getUnsettledCount();
      }
    }
    const double om_ms = 1e3 * median(t_octomap), ours_ms = 1e3 * median(t_ours);
    table.add({seq.name, std::to_string(seq.scans.size()), format("%.1f", om_ms), format("%.1f", ours_ms),
               format("%.1f×", om_ms / ours_ms), format("%.1f", 1e3 * median(t_binary)),
               std::to_string(octomap_bytes), std::to_string(our_bytes),
               format("1/%.1f", double(octomap_bytes) / double(our_bytes)), std::to_string(unsettled)});
  }
  return "## Multi-scan mapping: log-odds next to OctoMap\n\n"
         "Each sequence inserted scan by scan from an empty map, " +
         std::to_string(repeats) +
         " times, medians. OctoMap 1.9's `OcTree::insertPointCloud` (its sensor model's defaults, no "
         "discretize, single-threaded as Debian builds it) next to `insertRays` by the log-odds rule, which "
         "gives every cell OctoMap's float bit for bit (`test_log_odds_mapping`), and by the binary rule. "
         "Memory: OctoMap's `memoryUsage()` (its nodes, without malloc's overhead) and our "
         "`getMemoryBytes()` "
         "after `shrinkToFit()` (pool, free blocks included, value blocks and their index, the palette). "
         "Goal: 25× OctoMap's speed and at most 1/5 of its memory.\n\n" +
         table.markdown();
}

}  // namespace fot_bench
