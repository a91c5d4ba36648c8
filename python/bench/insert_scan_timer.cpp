// The C++ side of the binding's overhead benchmark (bench_tiles.py): inserts one scan file into fresh
// log-odds maps with the same call the binding makes, and prints each insertion's seconds.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include <pcl_fot/io/file_io.h>
#include <pcl_fot/mapping/scan_insertion.h>

#include "cloud_parser.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s <scan.pcd> <resolution> <repeats>\n", argv[0]);
    return 1;
  }
  try {
    const std::string bytes = pcl::fot::io::readFile(argv[1], std::size_t(8) << 30);
    const fot_tools::XyzCloud cloud = fot_tools::parsePcd(bytes.data(), bytes.size());
    pcl::fot::ScanOptions options;
    options.threads = 1;
    for (int r = std::atoi(argv[3]); r > 0; --r) {
      pcl::fot::FastOctTree map(std::atof(argv[2]));
      map.setUpdateRule(pcl::fot::UpdateRule::LogOdds);
      const auto start = std::chrono::steady_clock::now();
      pcl::fot::insertRays(map, cloud.origin, cloud.xyz.data(), cloud.xyz.size() / 3, 3 * sizeof(float),
                           options);
      std::printf("%.6f\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}
