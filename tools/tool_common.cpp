#include "tool_common.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <sstream>

#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/octomap_bt.h>

namespace fot_tools {
namespace {

bool looksLikeNumber(const std::string& s) {
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return end != s.c_str() && *end == '\0';
}

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

Arguments::Arguments(int argc, char** argv, std::set<std::string> valued, std::set<std::string> switches)
    : argc_(argc), argv_(argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.size() > 1 && a[0] == '-' && !looksLikeNumber(a)) {
      if (valued.count(a)) {
        if (i + 1 >= argc) throw ToolError(kExitUsage, "option " + a + " needs a value (see -h)");
        ++i;
      } else if (!switches.count(a)) {
        throw ToolError(kExitUsage, "unknown option " + a + " (see -h)");
      }
      continue;
    }
    positional_.push_back(a);
  }
}

bool Arguments::get(const std::string& name, double& value) const {
  if (pcl::console::find_argument(argc_, argv_, name.c_str()) < 0) return false;
  if (pcl::console::parse_argument(argc_, argv_, name.c_str(), value) < 0 || !std::isfinite(value))
    throw ToolError(kExitUsage, "option " + name + " needs a finite number");
  return true;
}

bool Arguments::get(const std::string& name, int& value) const {
  if (pcl::console::find_argument(argc_, argv_, name.c_str()) < 0) return false;
  if (pcl::console::parse_argument(argc_, argv_, name.c_str(), value) < 0)
    throw ToolError(kExitUsage, "option " + name + " needs a whole number");
  return true;
}

bool Arguments::get(const std::string& name, std::string& value) const {
  return pcl::console::parse_argument(argc_, argv_, name.c_str(), value) >= 0;
}

bool Arguments::get(const std::string& name, std::vector<double>& values, std::size_t count) const {
  std::string text;
  if (!get(name, text)) return false;
  values.clear();
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v))
      throw ToolError(kExitUsage,
                      "option " + name + " takes " + std::to_string(count) + " comma-separated numbers");
    values.push_back(v);
  }
  if (values.size() != count)
    throw ToolError(kExitUsage,
                    "option " + name + " takes " + std::to_string(count) + " comma-separated numbers");
  return true;
}

bool Arguments::getPositive(const std::string& name, double& value) const {
  if (!get(name, value)) return false;
  if (!(value > 0)) throw ToolError(kExitUsage, "option " + name + " must be positive");
  return true;
}

std::string extension(const std::string& path) {
  const std::size_t dot = path.rfind('.');
  if (dot == std::string::npos || path.find('/', dot) != std::string::npos) return "";
  std::string e = path.substr(dot);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

pcl::PointCloud<pcl::PointXYZ>::Ptr loadCloud(const std::string& path) {
  const std::string ext = extension(path);
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int status;
  {
    QuietPcl quiet;
    if (ext == ".pcd")
      status = pcl::io::loadPCDFile(path, blob, origin, orientation);
    else if (ext == ".ply")
      status = pcl::io::loadPLYFile(path, blob, origin, orientation);
    else
      throw ToolError(kExitUsage, "'" + path + "' is not a .pcd or .ply point cloud");
  }
  if (status != 0) throw ToolError(kExitInput, "cannot read the point cloud '" + path + "'");
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud = xyzOf(blob, path);
  cloud->sensor_origin_ = origin;
  cloud->sensor_orientation_ = orientation;
  return cloud;
}

bool isMapFile(const std::string& path) {
  const std::string ext = extension(path);
  return ext == ".fot" || ext == ".bt";
}

pcl::fot::FastOctTree loadMap(const std::string& path) {
  const std::string ext = extension(path);
  if (ext == ".fot") return pcl::fot::io::loadFot(path);
  if (ext == ".bt") return pcl::fot::io::loadBt(path);
  throw ToolError(kExitUsage, "'" + path + "' is not a .fot or .bt map");
}

}  // namespace fot_tools
