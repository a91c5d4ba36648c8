#include "cloud_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>

#include "cloud_parser.h"
#include "tool_common.h"

namespace fot_tools {
namespace {

/** A file's bytes, mapped read-only: the parsers read only what they need, and allocate nothing for it. */
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || ::fstat(fd, &st) != 0) {
      if (fd >= 0) ::close(fd);
      throw ToolError(kExitInput, "cannot read the point cloud '" + path + "'");
    }
    size_ = std::size_t(st.st_size);
    if (size_ > 0) {
      void* at = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      if (at != MAP_FAILED) data_ = static_cast<const char*>(at);
    }
    ::close(fd);
    if (size_ > 0 && !data_) throw ToolError(kExitInput, "cannot read the point cloud '" + path + "'");
  }
  ~MappedFile() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  const char* data() const { return data_ ? data_ : ""; }
  std::size_t size() const { return size_; }

 private:
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace

pcl::PointCloud<pcl::PointXYZ>::Ptr loadCloud(const std::string& path) {
  const std::string ext = extension(path);
  if (ext != ".pcd" && ext != ".ply")
    throw ToolError(kExitUsage, "'" + path + "' is not a .pcd or .ply point cloud");
  requireRegularFile(path, "the point cloud");
  XyzCloud parsed;
  {
    const MappedFile file(path);
    try {
      parsed = ext == ".pcd" ? parsePcd(file.data(), file.size()) : parsePly(file.data(), file.size());
    } catch (const CloudFileError& e) {
      throw ToolError(kExitInput, "'" + path + "' " + e.what());
    }
  }
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>(parsed.width, parsed.height));
  bool dense = true;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    pcl::PointXYZ& p = (*cloud)[i];
    p.x = parsed.xyz[3 * i], p.y = parsed.xyz[3 * i + 1], p.z = parsed.xyz[3 * i + 2];
    dense = dense && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  }
  cloud->is_dense = dense;
  cloud->sensor_origin_ = Eigen::Vector4f(parsed.origin[0], parsed.origin[1], parsed.origin[2], 0.0f);
  cloud->sensor_orientation_ = Eigen::Quaternionf(parsed.orientation[0], parsed.orientation[1],
                                                  parsed.orientation[2], parsed.orientation[3]);
  return cloud;
}

}  // namespace fot_tools
