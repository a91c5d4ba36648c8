// Multi-scan mapping: the log-odds rule and the binary rule next to OctoMap's insertPointCloud.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <octomap/OcTree.h>
#include <Eigen/Geometry>

#include <pcl_fot/mapping/scan_insertion.h>
#include <pcl_fot/tree/accessor.h>
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

/** Equal canonical pools, the values compared as bits: an unknown cell's value is NaN. */
bool samePool(const pcl::fot::FastOctTree& a, const pcl::fot::FastOctTree& b) {
  const pcl::fot::FastOctTree::CanonicalPool pa = a.canonicalPool(), pb = b.canonicalPool();
  return pa.words == pb.words && pa.values.size() == pb.values.size() &&
         (pa.values.empty() ||
          std::memcmp(pa.values.data(), pb.values.data(), pa.values.size() * sizeof(float)) == 0);
}

/** Every cell OctoMap knows holds OctoMap's log-odds in `ours`, bit for bit, and ours knows no other. */
bool sameAsOctoMap(const octomap::OcTree& om, const pcl::fot::FastOctTree& ours) {
  pcl::fot::ConstAccessor cells(ours);
  std::uint64_t known = 0;
  for (auto it = om.begin_leafs(); it != om.end_leafs(); ++it) {
    const int side = 1 << (16 - it.getDepth());
    const octomap::OcTreeKey base = it.getIndexKey();  // OctoMap's key: ours + 32768
    const float want = it->getLogOdds();
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
          const float got = cells.getLogOdds(
              pcl::fot::Key{int(base[0]) - 32768 + x, int(base[1]) - 32768 + y, int(base[2]) - 32768 + z});
          if (std::memcmp(&got, &want, sizeof got) != 0) return false;
        }
    known += std::uint64_t(side) * side * side;
  }
  return known == ours.getFreeCount() + ours.getOccupiedCount();
}

}  // namespace

std::string benchMultiScan(const std::vector<BenchScan>& scans, int repeats) {
  Table table({"sequence", "scans", "cells passed / distinct", "stepped / distinct", "OctoMap ms",
               "log-odds ms", "speed-up", "log-odds 2 threads ms", "2 threads / 1", "binary ms",
               "binary 2 threads ms", "bit for bit OctoMap", "OctoMap bytes", "log-odds bytes as inserted",
               "after shrinkToFit", "memory ratio as inserted", "after shrinkToFit", "unsettled cells",
               "equal"});
  for (const Sequence& seq : sequences(scans)) {
    std::vector<double> t_octomap, t_log[2], t_binary[2];
    std::size_t octomap_bytes = 0, inserted_bytes = 0, our_bytes = 0;
    std::uint64_t unsettled = 0, walked = 0, skipped = 0, distinct = 0;
    bool equal = true, exact = true;
    for (int r = 0; r < repeats; ++r) {
      octomap::OcTree om(seq.resolution);
      t_octomap.push_back(timeOnce([&] {
        for (const Scan& s : seq.scans)
          om.insertPointCloud(s.finite, octomap::point3d(s.sensor[0], s.sensor[1], s.sensor[2]));
      }));
      octomap_bytes = om.memoryUsage();
      for (pcl::fot::UpdateRule rule : {pcl::fot::UpdateRule::LogOdds, pcl::fot::UpdateRule::Binary}) {
        std::vector<pcl::fot::FastOctTree> maps;
        for (unsigned threads : {1u, 2u}) {
          pcl::fot::FastOctTree tree(seq.resolution);
          tree.setUpdateRule(rule);
          pcl::fot::ScanOptions options;
          options.threads = threads;
          walked = skipped = distinct = 0;
          const double t = timeOnce([&] {
            for (const Scan& s : seq.scans) {
              const pcl::fot::ScanStats stats = pcl::fot::insertRays(
                  tree, s.sensor, s.xyz.data(), s.xyz.size() / 3, 3 * sizeof(float), options);
              walked += stats.ray_cells;
              skipped += stats.skipped_cells;
              distinct += stats.free_cells;
            }
          });
          (rule == pcl::fot::UpdateRule::Binary ? t_binary : t_log)[threads - 1].push_back(t);
          maps.push_back(std::move(tree));
        }
        equal = equal && samePool(maps[0], maps[1]);
        if (rule == pcl::fot::UpdateRule::Binary) continue;
        if (r == 0) exact = sameAsOctoMap(om, maps[0]);
        inserted_bytes = maps[0].getMemoryBytes();
        maps[0].shrinkToFit();
        our_bytes = maps[0].getMemoryBytes();
        unsettled = maps[0].getUnsettledCount();
      }
    }
    const double om_ms = 1e3 * median(t_octomap), log_ms = 1e3 * median(t_log[0]),
                 log2_ms = 1e3 * median(t_log[1]);
    table.add({seq.name, std::to_string(seq.scans.size()), format("%.1f", double(walked) / double(distinct)),
               format("%.1f", double(walked - skipped) / double(distinct)), format("%.1f", om_ms),
               format("%.1f", log_ms), format("%.1f×", om_ms / log_ms), format("%.1f", log2_ms),
               format("%.2f×", log_ms / log2_ms), format("%.1f", 1e3 * median(t_binary[0])),
               format("%.1f", 1e3 * median(t_binary[1])), exact ? "yes" : "NO", std::to_string(octomap_bytes),
               std::to_string(inserted_bytes), std::to_string(our_bytes),
               format("1/%.1f", double(octomap_bytes) / double(inserted_bytes)),
               format("1/%.1f", double(octomap_bytes) / double(our_bytes)), std::to_string(unsettled),
               equal ? "yes" : "NO"});
  }
  return "## Multi-scan mapping: log-odds next to OctoMap\n\n"
         "Each sequence inserted scan by scan from an empty map, " +
         std::to_string(repeats) +
         " times, medians. OctoMap 1.9's `OcTree::insertPointCloud` (its sensor model's defaults, no "
         "discretize, single-threaded as Debian builds it) next to `insertRays` by the log-odds rule, which "
         "gives every cell OctoMap's float bit for bit (`test_log_odds_mapping`), and by the binary rule, "
         "each "
         "on one thread and on two (`ScanOptions::threads`). *Bit for bit OctoMap*: every cell OctoMap's map "
         "knows holds its log-odds, bits compared, in ours (one thread, first repetition), and ours knows no "
         "other cell. *Equal*: the maps built on one and on two "
         "threads have the same canonical pool, word for word and value for value. *Cells passed / "
         "distinct*: the cells the rays pass, summed over rays, against the distinct cells the scans mark "
         "free (`ScanStats::ray_cells` and `free_cells`): how often a cell is passed again within a scan. "
         "*Stepped / distinct*: the same for the cells the walks step through one by one, the stretches "
         "near the sensor that ray bundles mark once left out (`skipped_cells`). "
         "Memory: OctoMap's `memoryUsage()` (its nodes, without malloc's overhead) and our "
         "`getMemoryBytes()` (pool, free blocks included, value rows and their index, the palette) as "
         "inserted and after `shrinkToFit()`. "
         "Goal: 30× OctoMap's speed on one thread, 1.7× that on two, and at most 1/5 of its memory.\n\n" +
         table.markdown();
}

}  // namespace fot_bench
