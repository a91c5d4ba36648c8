#pragma once
// Point cloud files (.pcd, .ply) for the tools, read so that a damaged file costs no more than its size.

#include <string>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace fot_tools {

/**
 * Reads x, y, z (float or double) of a .pcd or .ply point cloud and its sensor pose, with the parsers of
 * cloud_parser.h. Throws ToolError with one line for a file it cannot use.
 */
pcl::PointCloud<pcl::PointXYZ>::Ptr loadCloud(const std::string& path);

}  // namespace fot_tools
