#include "cloud_file.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include "tool_common.h"

namespace fot_tools {
namespace {

/** Silences PCL's console while a PCL reader runs: its errors come back to us as one line. */
class QuietPcl {
 public:
  QuietPcl() : level_(pcl::console::getVerbosityLevel()) {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  }
  ~QuietPcl() { pcl::console::setVerbosityLevel(level_); }

 private:
  pcl::console::VERBOSITY_LEVEL level_;
};

/** a·b, or the largest value where that overflows: claims are compared, never allocated. */
std::uint64_t times(std::uint64_t a, std::uint64_t b) {
  return b != 0 && a > std::numeric_limits<std::uint64_t>::max() / b
             ? std::numeric_limits<std::uint64_t>::max()
             : a * b;
}

/** A line of a header, split into words. False at the end of the file, and for a line longer than any
 * header's: a binary file need not hold a line end at all. */
bool headerLine(std::istream& in, std::vector<std::string>& words) {
  std::string line;
  if (!readLine(in, line, 1 << 20)) return false;
  std::istringstream split(line);
  words.clear();
  for (std::string w; split >> w;) words.push_back(w);
  return true;
}

std::uint64_t number(const std::string& word) {
  char* end = nullptr;
  const unsigned long long v = std::strtoull(word.c_str(), &end, 10);
  return *end == '\0' && word[0] != '-' ? v : 0;
}

/**
 * The fewest bytes the data after a PCD header can hold its points in: all of them in binary, an 88th
 * compressed (LZF's best ratio), a character and a separator a value in ASCII. False if the header does
 * not end in a DATA line.
 */
bool pcdDataBytes(std::istream& in, std::uint64_t& bytes) {
  std::vector<std::string> w;
  std::vector<std::uint64_t> sizes, counts;
  std::uint64_t width = 0, height = 0, points = 0;
  while (headerLine(in, w)) {
    if (w.empty() || w[0][0] == '#') continue;
    if (w[0] == "SIZE" || w[0] == "COUNT") {
      auto& list = w[0] == "SIZE" ? sizes : counts;
      for (std::size_t i = 1; i < w.size(); ++i) list.push_back(number(w[i]));
    } else if (w.size() > 1 && (w[0] == "WIDTH" || w[0] == "HEIGHT" || w[0] == "POINTS")) {
      (w[0] == "WIDTH" ? width : w[0] == "HEIGHT" ? height : points) = number(w[1]);
    } else if (w[0] == "DATA" && w.size() > 1) {
      counts.resize(sizes.size(), 1);
      std::uint64_t point_bytes = 0, values = 0;
      for (std::size_t i = 0; i < sizes.size(); ++i)
        point_bytes += times(sizes[i], counts[i]), values += counts[i];
      points = std::max(points, times(width, height));
      const std::uint64_t chars = times(points, 2 * values);
      bytes = w[1] == "binary"              ? times(points, point_bytes)
              : w[1] == "binary_compressed" ? times(points, point_bytes) / 88
              : chars                       ? chars - 1
                                            : 0;
      return true;
    }
  }
  return false;
}

/**
 * The same for a PLY header, over all its elements: whole in binary, two characters a value in ASCII.
 * False if the header does not end in end_header.
 */
bool plyDataBytes(std::istream& in, std::uint64_t& bytes) {
  std::vector<std::string> w;
  if (!headerLine(in, w) || w.empty() || w[0] != "ply") return false;
  bool ascii = false;
  std::uint64_t total = 0, count = 0, item_bytes = 0;
  auto typeBytes = [](const std::string& t) -> std::uint64_t {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "double" || t == "float64") return 8;
    return 4;
  };
  while (headerLine(in, w)) {
    if (w.empty()) continue;
    if (w[0] == "format" && w.size() > 1) {
      ascii = w[1] == "ascii";
    } else if (w[0] == "element" && w.size() > 2) {
      total += times(count, item_bytes);
      count = number(w[2]), item_bytes = 0;
    } else if (w[0] == "property" && w.size() > 2) {
      // A list holds at least its length.
      item_bytes += ascii ? 2 : typeBytes(w[1] == "list" ? w[2] : w[1]);
    } else if (w[0] == "end_header") {
      total += times(count, item_bytes);
      bytes = ascii && total ? total - 1 : total;  // the last value needs no separator
      return true;
    }
  }
  return false;
}

/**
 * PCL's readers allocate what the header claims before they read: a damaged count in a file of a few bytes
 * would cost gigabytes. Refuses a file that is not a regular file (a device could be read forever), a
 * header that never ends (PCL 1.13 crashes on an empty PCD file, and reads one without DATA as no points),
 * and a header whose points cannot fit in the rest of the file.
 */
void checkClaim(const std::string& path, const std::string& ext) {
  requireRegularFile(path, "the point cloud");
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  std::uint64_t needed = 0;
  if (!(ext == ".pcd" ? pcdDataBytes(in, needed) : plyDataBytes(in, needed)))
    throw ToolError(kExitInput, "'" + path + "' is damaged or truncated: its " +
                                    (ext == ".pcd" ? "PCD header has no DATA line"
                                                   : "PLY header has no end_header line"));
  in.clear();
  const std::streamoff data_start = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (data_start < 0 || size < data_start) return;
  if (needed > std::uint64_t(size - data_start))
    throw ToolError(kExitInput, "'" + path +
                                    "' is damaged or truncated: its header claims more points than its " +
                                    std::to_string(size) + " bytes hold");
}

/** Field `f` of the point at `point`, a float or a double, as a float; beyond float's range, an infinity. */
float coordinate(const std::uint8_t* point, const pcl::PCLPointField& f) {
  if (f.datatype == pcl::PCLPointField::FLOAT32) {
    float v;
    std::memcpy(&v, point + f.offset, sizeof v);
    return v;
  }
  double v;
  std::memcpy(&v, point + f.offset, sizeof v);
  if (std::isnan(v) || std::abs(v) <= std::numeric_limits<float>::max()) return float(v);
  return std::copysign(std::numeric_limits<float>::infinity(), float(v));
}

/**
 * The cloud's x, y, z, stored as floats or doubles. PCL's fromPCLPointCloud2 would leave every point at
 * (0, 0, 0) for doubles, and for a cloud without x, y, z, without a word.
 */
pcl::PointCloud<pcl::PointXYZ>::Ptr xyzOf(const pcl::PCLPointCloud2& blob, const std::string& path) {
  const pcl::PCLPointField* axes[3] = {nullptr, nullptr, nullptr};
  for (const auto& f : blob.fields)
    for (int a = 0; a < 3; ++a)
      if (f.name == std::string(1, char('x' + a))) axes[a] = &f;
  for (const pcl::PCLPointField* f : axes) {
    if (!f) throw ToolError(kExitInput, "'" + path + "' has no x, y, z fields");
    const std::size_t bytes = f->datatype == pcl::PCLPointField::FLOAT32   ? 4
                              : f->datatype == pcl::PCLPointField::FLOAT64 ? 8
                                                                           : 0;
    if (bytes == 0)
      throw ToolError(kExitInput,
                      "'" + path + "' stores " + f->name + " as an integer; float or double needed");
    if (f->offset + bytes > blob.point_step)
      throw ToolError(kExitInput, "'" + path + "' has a field " + f->name + " beyond its point size");
  }
  if (std::uint64_t(blob.width) * blob.point_step > blob.row_step ||
      std::uint64_t(blob.row_step) * blob.height > blob.data.size())
    throw ToolError(kExitInput, "'" + path + "' holds fewer bytes than its points need");
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>(blob.width, blob.height));
  cloud->is_dense = blob.is_dense;
  for (std::uint32_t r = 0; r < blob.height; ++r)
    for (std::uint32_t c = 0; c < blob.width; ++c) {
      const std::uint8_t* point =
          blob.data.data() + std::size_t(r) * blob.row_step + std::size_t(c) * blob.point_step;
      pcl::PointXYZ& p = (*cloud)(c, r);
      p.x = coordinate(point, *axes[0]), p.y = coordinate(point, *axes[1]), p.z = coordinate(point, *axes[2]);
    }
  return cloud;
}

}  // namespace

pcl::PointCloud<pcl::PointXYZ>::Ptr loadCloud(const std::string& path) {
  const std::string ext = extension(path);
  if (ext != ".pcd" && ext != ".ply")
    throw ToolError(kExitUsage, "'" + path + "' is not a .pcd or .ply point cloud");
  checkClaim(path, ext);
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int status;
  {
    QuietPcl quiet;
    status = ext == ".pcd" ? pcl::io::loadPCDFile(path, blob, origin, orientation)
                           : pcl::io::loadPLYFile(path, blob, origin, orientation);
  }
  if (status != 0) throw ToolError(kExitInput, "cannot read the point cloud '" + path + "'");
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud = xyzOf(blob, path);
  cloud->sensor_origin_ = origin;
  cloud->sensor_orientation_ = orientation;
  return cloud;
}

}  // namespace fot_tools
