// The tools' point cloud reader: what PCL writes loads exactly, and damaged files fail before any big
// allocation.
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <unistd.h>

#include "cloud_file.h"
#include "tool_common.h"

namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("pcl_fot_cloud_file_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

/** Points on a 1/8 grid: exact in float, double and PCL's ASCII. */
pcl::PointCloud<pcl::PointXYZRGBNormal> gridCloud(std::size_t n) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> eighths(-80, 80);
  pcl::PointCloud<pcl::PointXYZRGBNormal> cloud;
  for (std::size_t i = 0; i < n; ++i) {
    pcl::PointXYZRGBNormal p;
    p.x = eighths(rng) / 8.0f, p.y = eighths(rng) / 8.0f, p.z = eighths(rng) / 8.0f;
    p.r = 200, p.normal_x = 1;
    cloud.push_back(p);
  }
  cloud.sensor_origin_ = Eigen::Vector4f(1, 2, 3, 0);
  return cloud;
}

void expectSameXyz(const pcl::PointCloud<pcl::PointXYZRGBNormal>& written,
                   const pcl::PointCloud<pcl::PointXYZ>& read) {
  ASSERT_EQ(read.size(), written.size());
  for (std::size_t i = 0; i < read.size(); ++i)
    ASSERT_EQ(read[i].getVector3fMap(), written[i].getVector3fMap()) << "point " << i;
  EXPECT_EQ(read.sensor_origin_, written.sensor_origin_);
}

TEST(CloudFile, ReadsXyzAmongOtherFieldsInEveryLayoutPclWrites) {
  const auto cloud = gridCloud(500);
  const std::string path = tempPath("layouts.pcd");
  for (int layout = 0; layout < 3; ++layout) {
    if (layout == 0) pcl::io::savePCDFileASCII(path, cloud);
    if (layout == 1) pcl::io::savePCDFileBinary(path, cloud);
    if (layout == 2) pcl::io::savePCDFileBinaryCompressed(path, cloud);
    expectSameXyz(cloud, *fot_tools::loadCloud(path));
  }
  const std::string ply = tempPath("layouts.ply");
  pcl::io::savePLYFileBinary(ply, cloud);
  const auto read = fot_tools::loadCloud(ply);
  ASSERT_EQ(read->size(), cloud.size());
  for (std::size_t i = 0; i < read->size(); ++i)
    ASSERT_EQ((*read)[i].getVector3fMap(), cloud[i].getVector3fMap());
  std::filesystem::remove(path);
  std::filesystem::remove(ply);
}

TEST(CloudFile, CompressedFramesAtLzfsBestRatioStillLoad) {
  // One point repeated over a whole organised frame compresses about 88-fold, LZF's limit: the size
  // check must still let it through.
  pcl::PointCloud<pcl::PointXYZ> frame(640, 480, pcl::PointXYZ(0, 0, 0));
  const std::string path = tempPath("flat.pcd");
  pcl::io::savePCDFileBinaryCompressed(path, frame);
  EXPECT_GT(frame.size() * sizeof(float) * 3, 80 * std::filesystem::file_size(path))
      << "the frame should compress close to LZF's limit";
  const auto read = fot_tools::loadCloud(path);
  EXPECT_EQ(read->width, 640u);
  EXPECT_EQ(read->height, 480u);
  std::filesystem::remove(path);
}

TEST(CloudFile, EveryTruncationFailsWithOneMessage) {
  const auto cloud = gridCloud(300);
  const std::string whole = tempPath("whole.pcd"), cut = tempPath("cut.pcd");
  for (bool compressed : {false, true}) {
    if (compressed)
      pcl::io::savePCDFileBinaryCompressed(whole, cloud);
    else
      pcl::io::savePCDFileBinary(whole, cloud);
    std::ifstream in(whole, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::size_t header = bytes.find("DATA");
    ASSERT_NE(header, std::string::npos);
    // From the empty file (PCL 1.13 crashes on it) through the header (PCL reads one without DATA as no
    // points) into the data.
    for (std::size_t size = 0; size < bytes.size(); size += size < header + 8 ? 3 : 97) {
      std::ofstream(cut, std::ios::binary).write(bytes.data(), std::streamsize(size));
      try {
        fot_tools::loadCloud(cut);
        ADD_FAILURE() << "a file cut at " << size << " of " << bytes.size() << " bytes loaded";
      } catch (const fot_tools::ToolError& e) {
        EXPECT_EQ(e.code, fot_tools::kExitInput);
        if (!compressed && size > bytes.find('\n', header)) {
          EXPECT_NE(std::string(e.what()).find("damaged or truncated"), std::string::npos) << e.what();
        }
      }
    }
  }
  std::filesystem::remove(whole);
  std::filesystem::remove(cut);
}

TEST(CloudFile, WhatIsNotACloudFileFailsWithoutReadingItAll) {
  auto expectRefused = [](const std::string& path, const std::string& words) {
    try {
      fot_tools::loadCloud(path);
      ADD_FAILURE() << path << " loaded";
    } catch (const fot_tools::ToolError& e) {
      EXPECT_EQ(e.code, fot_tools::kExitInput);
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  // A device has no end: it is refused before it is read.
  const std::string device = tempPath("device.pcd");
  std::filesystem::create_symlink("/dev/zero", device);
  expectRefused(device, "not a regular file");
  std::filesystem::remove(device);
  // Lines no header has: 4 MiB without a line end.
  const std::string blob = tempPath("blob.ply");
  std::ofstream(blob, std::ios::binary) << "ply\n" << std::string(4 << 20, 'x');
  expectRefused(blob, "no end_header line");
  std::filesystem::remove(blob);
}

}  // namespace
