// The tools' point cloud reader: what PCL writes loads exactly, and damaged files fail with one line,
// before any big allocation, where PCL's own readers crash.
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <pcl/conversions.h>
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

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/** Loads the file, or returns nullptr if it is refused, as it must be, with one line and exit code 2. */
pcl::PointCloud<pcl::PointXYZ>::Ptr loadOrRefuse(const std::string& path) {
  try {
    return fot_tools::loadCloud(path);
  } catch (const fot_tools::ToolError& e) {
    EXPECT_EQ(e.code, fot_tools::kExitInput) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return nullptr;
  }
}

TEST(CloudFile, PlyInEveryLayoutKeepsTheOrganisedShapeAndThePose) {
  auto cloud = gridCloud(12);
  cloud.width = 4, cloud.height = 3;
  cloud[5].x = cloud[5].y = cloud[5].z = std::numeric_limits<float>::quiet_NaN();
  cloud.sensor_orientation_ = Eigen::Quaternionf(Eigen::AngleAxisf(0.5f, Eigen::Vector3f(0, 0.6f, 0.8f)));
  const std::string path = tempPath("organised.ply");
  auto expectSame = [&](const pcl::PointCloud<pcl::PointXYZ>& read, bool pose) {
    ASSERT_EQ(read.width, 4u);
    ASSERT_EQ(read.height, 3u);
    for (std::size_t i = 0; i < read.size(); ++i) {
      if (i == 5) {
        EXPECT_TRUE(std::isnan(read[i].x)) << "the NaN point stays in its cell";
        continue;
      }
      ASSERT_EQ(read[i].getVector3fMap(), cloud[i].getVector3fMap()) << "point " << i;
    }
    if (!pose) return;
    EXPECT_EQ(read.sensor_origin_, cloud.sensor_origin_);
    EXPECT_LT(read.sensor_orientation_.angularDistance(cloud.sensor_orientation_), 1e-6f);
  };
  // With a camera element, as savePLYFile writes by default: PCL's reader loses its pose, ours keeps it.
  for (bool binary : {false, true}) {
    pcl::io::savePLYFile(path, cloud, binary);
    expectSame(*fot_tools::loadCloud(path), true);
  }
  // Without one: obj_info gives the shape and the origin, and a range_grid the cell of each vertex.
  pcl::PCLPointCloud2 blob;
  pcl::toPCLPointCloud2(cloud, blob);
  for (bool binary : {false, true}) {
    pcl::PLYWriter().write(path, blob, cloud.sensor_origin_, Eigen::Quaternionf::Identity(), binary, false);
    const auto read = fot_tools::loadCloud(path);
    expectSame(*read, false);
    EXPECT_EQ(read->sensor_origin_, cloud.sensor_origin_);
  }
  std::filesystem::remove(path);
}

/** The bytes of v, most significant first (the host is little-endian). */
template <typename T>
std::string bigEndian(T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  std::reverse(b, b + sizeof(T));
  return std::string(b, sizeof(T));
}

TEST(CloudFile, BigEndianPlyAndDoublePcd) {
  const std::string ply = tempPath("big.ply"), pcd = tempPath("doubles.pcd");
  auto writePly = [&](bool integer_z) {
    std::ofstream out(ply, std::ios::binary);
    out << "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty uchar red\nproperty double x\n"
        << "property float y\nproperty " << (integer_z ? "int" : "float") << " z\nend_header\n";
    const double xyz[2][3] = {{1.5, -2.0, -3.0}, {0.0, 0.25, 4.0}};
    for (const auto& p : xyz)
      out << char(7) << bigEndian(p[0]) << bigEndian(float(p[1]))
          << (integer_z ? bigEndian(std::int32_t(p[2])) : bigEndian(float(p[2])));
  };
  writePly(true);
  try {
    fot_tools::loadCloud(ply);
    ADD_FAILURE() << "an integer z loaded";
  } catch (const fot_tools::ToolError& e) {
    EXPECT_NE(std::string(e.what()).find("stores z as an integer"), std::string::npos) << e.what();
  }
  writePly(false);
  const auto read = fot_tools::loadCloud(ply);
  ASSERT_EQ(read->size(), 2u);
  EXPECT_EQ((*read)[0].getVector3fMap(), Eigen::Vector3f(1.5f, -2.0f, -3.0f));
  EXPECT_EQ((*read)[1].getVector3fMap(), Eigen::Vector3f(0.0f, 0.25f, 4.0f));

  std::ofstream(pcd)
      << "# a comment\nVERSION .7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\n"
         "HEIGHT 1\nVIEWPOINT 1 2 3 1 0 0 0\nPOINTS 3\nDATA ascii\n0.125 -2 1e300\nnan +4 -1e-400\n"
         "1 2 3";
  const auto doubles = fot_tools::loadCloud(pcd);
  ASSERT_EQ(doubles->size(), 3u);
  EXPECT_EQ((*doubles)[0].x, 0.125f);
  EXPECT_EQ((*doubles)[0].z, std::numeric_limits<float>::infinity()) << "beyond float's range";
  EXPECT_TRUE(std::isnan((*doubles)[1].x));
  EXPECT_EQ((*doubles)[1].y, 4.0f);
  EXPECT_EQ((*doubles)[1].z, 0.0f) << "below double's range";
  EXPECT_EQ((*doubles)[2].getVector3fMap(), Eigen::Vector3f(1, 2, 3)) << "the last value needs no line end";
  EXPECT_FALSE(doubles->is_dense);
  EXPECT_EQ(doubles->sensor_origin_, Eigen::Vector4f(1, 2, 3, 0));
  std::filesystem::remove(ply);
  std::filesystem::remove(pcd);
}

TEST(CloudFile, EveryTruncationOfAPlyOrAsciiPcdFails) {
  const auto cloud = gridCloud(40);
  const std::string whole = tempPath("whole"), cut = tempPath("cut");
  for (int layout = 0; layout < 3; ++layout) {
    const std::string ext = layout == 0 ? ".pcd" : ".ply";
    if (layout == 0) pcl::io::savePCDFileASCII(whole + ext, cloud);
    if (layout > 0) pcl::io::savePLYFile(whole + ext, cloud, layout == 2);
    const std::string bytes = fileBytes(whole + ext);
    // Every cut before the last value's last byte: only a text file's final line end may go.
    const std::size_t needed = layout < 2 ? bytes.size() - 1 : bytes.size();
    for (std::size_t size = 0; size < needed; size += size + 7 < needed ? 5 : 1) {
      std::ofstream(cut + ext, std::ios::binary).write(bytes.data(), std::streamsize(size));
      EXPECT_EQ(loadOrRefuse(cut + ext), nullptr) << ext << " cut at " << size << " of " << bytes.size();
    }
    std::filesystem::remove(whole + ext);
  }
  std::filesystem::remove(cut + ".pcd");
  std::filesystem::remove(cut + ".ply");
}

TEST(CloudFile, DamagedFilesAreRefusedWithOneLineWherePclCrashes) {
  // Inputs the fuzzer found: PCL 1.13's PCDReader dereferences null on the first, and its PLYReader fails
  // an assertion on the second.
  const std::string regressions = std::string(PCL_FOT_SOURCE_DIR) + "/fuzz/regressions/cloud_parser/";
  EXPECT_EQ(loadOrRefuse(regressions + "pcl_segfaults_without_fields.pcd"), nullptr);
  EXPECT_EQ(loadOrRefuse(regressions + "pcl_asserts_on_a_damaged_property.ply"), nullptr);

  // Random damage to every layout PCL writes: each file loads or is refused, and never crashes.
  auto cloud = gridCloud(30);
  cloud.width = 6, cloud.height = 5;
  const std::string path = tempPath("damaged");
  std::mt19937 rng(11);
  std::size_t refused = 0, tried = 0;
  for (int layout = 0; layout < 5; ++layout) {
    const std::string ext = layout < 3 ? ".pcd" : ".ply";
    if (layout == 0) pcl::io::savePCDFileASCII(path + ext, cloud);
    if (layout == 1) pcl::io::savePCDFileBinary(path + ext, cloud);
    if (layout == 2) pcl::io::savePCDFileBinaryCompressed(path + ext, cloud);
    if (layout >= 3) pcl::io::savePLYFile(path + ext, cloud, layout == 4);
    const std::string bytes = fileBytes(path + ext);
    for (int trial = 0; trial < 300; ++trial) {
      std::string damaged = bytes;
      for (int k = 0; k <= trial % 4; ++k)
        damaged[std::uniform_int_distribution<std::size_t>(0, damaged.size() - 1)(rng)] = char(rng());
      std::ofstream(path + ext, std::ios::binary) << damaged;
      const auto read = loadOrRefuse(path + ext);
      ++tried;
      if (!read) {
        ++refused;
        continue;
      }
      EXPECT_EQ(read->size(), std::size_t(read->width) * read->height);
    }
    std::filesystem::remove(path + ext);
  }
  EXPECT_GT(refused, tried / 10) << "header damage must be refused";
}

}  // namespace
