#pragma once

#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace fot_tools {

/**
 * The embedded default input: a furnished 8 m × 6 m × 3 m room with an open window, seen by a simulated
 * 160×120 depth camera from several poses. Fully deterministic.
 *
 * Each scan is organised like a depth image: points in the camera frame (z forward, x right, y down),
 * NaN where the ray leaves through the window or exceeds the range, and the camera pose in the map frame
 * in sensor_origin_ / sensor_orientation_, as PCL's grabbers and PCD VIEWPOINT do it.
 */
std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr> scanSyntheticRoom();

}  // namespace fot_tools
