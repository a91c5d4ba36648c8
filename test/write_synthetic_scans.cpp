// Writes the synthetic twins of the real scans as PCD files under the real scans' names, so that the tools'
// tests and the README example read them as they read PCL's scans. Usage: write_synthetic_scans <directory>
#include <filesystem>
#include <iostream>

#include <pcl/io/pcd_io.h>

#include "synthetic_scene.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: write_synthetic_scans <directory>\n";
    return 1;
  }
  std::filesystem::create_directories(argv[1]);
  for (const char* name : {"kinect_capture0001.pcd", "kinect_capture0002.pcd", "kinect_capture0003.pcd",
                           "room_scan1.pcd", "room_scan2.pcd", "terrain_samp11.pcd"}) {
    const auto cloud = fot_tools::syntheticTwin(name);
    const std::string path = std::string(argv[1]) + "/" + name;
    if (pcl::io::savePCDFileBinaryCompressed(path, *cloud) != 0) return 1;
    std::cout << path << ": " << cloud->size() << " points\n";
  }
  return 0;
}
