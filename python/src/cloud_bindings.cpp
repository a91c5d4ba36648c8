// Point cloud files read as the tools read them: points, organised size and sensor pose.

#include <string>

#include <pcl_fot/io/file_io.h>

#include "arrays.h"
#include "bindings.h"
#include "cloud_parser.h"

namespace pcl_fot_python {
namespace {

/** Cloud files larger than this are refused before they are read. */
constexpr std::size_t kMaxCloudBytes = std::size_t(8) << 30;

py::dict readCloud(const std::string& path) {
  fot_tools::XyzCloud cloud;
  {
    py::gil_scoped_release unlocked;
    const std::string bytes = pcl::fot::io::readFile(path, kMaxCloudBytes);
    const std::string e = extensionOf(path);
    try {
      if (e == ".pcd")
        cloud = fot_tools::parsePcd(bytes.data(), bytes.size());
      else if (e == ".ply")
        cloud = fot_tools::parsePly(bytes.data(), bytes.size());
      else
        throw std::invalid_argument("read_cloud: '" + path + "' must end in .pcd or .ply");
    } catch (const fot_tools::CloudFileError& e) {
      throw std::runtime_error("'" + path + "' " + e.what());
    }
  }
  py::array_t<float> points = newArray<float>(cloud.xyz.size() / 3, 3);
  std::copy(cloud.xyz.begin(), cloud.xyz.end(), points.mutable_data());
  py::dict d;
  d["points"] = points;
  d["width"] = cloud.width;
  d["height"] = cloud.height;
  d["origin"] = py::make_tuple(cloud.origin[0], cloud.origin[1], cloud.origin[2]);
  d["orientation"] =
      py::make_tuple(cloud.orientation[0], cloud.orientation[1], cloud.orientation[2], cloud.orientation[3]);
  return d;
}

}  // namespace

void bindClouds(py::module_& m) {
  m.def("read_cloud", &readCloud, py::arg("path"),
        "A .pcd or .ply file's points as an (N, 3) float32 array, with its organised size and sensor pose "
        "(origin, orientation as w, x, y, z).");
}

}  // namespace pcl_fot_python
