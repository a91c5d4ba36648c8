#include "bench_scans.h"

#include <cmath>
#include <stdexcept>

#include <pcl/common/common.h>

#include "../cloud_file.h"

namespace fot_bench {

namespace {

struct Spec {
  const char* name;
  double resolution;
  bool has_sensor;
};
const Spec kSpecs[] = {{"kinect_capture0001", 0.01, true}, {"kinect_capture0002", 0.01, true},
                       {"kinect_capture0003", 0.01, true}, {"room_scan1", 0.05, true},
                       {"room_scan2", 0.05, true},         {"terrain_samp11", 0.30, false}};

}  // namespace

std::vector<std::string> benchScanFiles(const std::string& data_dir) {
  std::vector<std::string> files;
  for (const Spec& s : kSpecs) files.push_back(data_dir + "/" + s.name + ".pcd");
  return files;
}

std::vector<BenchScan> loadBenchScans(const std::string& data_dir) {
  std::vector<BenchScan> scans;
  for (const Spec& s : kSpecs) {
    BenchScan scan{s.name, s.resolution, s.has_sensor, fot_tools::loadCloud(data_dir + "/" + s.name + ".pcd"),
                   0};
    if (!s.has_sensor) {
      pcl::PointXYZ lo, hi;
      pcl::getMinMax3D(*scan.cloud, lo, hi);
      const float cx = std::round(0.5f * (lo.x + hi.x)), cy = std::round(0.5f * (lo.y + hi.y)),
                  cz = std::round(0.5f * (lo.z + hi.z));
      for (auto& p : *scan.cloud) {
        p.x -= cx;
        p.y -= cy;
        p.z -= cz;
      }
    }
    for (const auto& p : *scan.cloud)
      scan.finite += std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    scans.push_back(scan);
  }
  return scans;
}

const BenchScan& findScan(const std::vector<BenchScan>& scans, const std::string& name) {
  for (const auto& s : scans)
    if (s.name == name) return s;
  throw std::runtime_error("missing scan " + name);
}

}  // namespace fot_bench
