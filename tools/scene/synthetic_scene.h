#pragma once

#include <string>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <Eigen/Geometry>

namespace fot_tools {

using SceneCloud = pcl::PointCloud<pcl::PointXYZ>;

/**
 * The embedded default input: a furnished 8 m × 6 m × 3 m room with an open window, seen by a simulated
 * 160×120 depth camera from several poses. Fully deterministic.
 *
 * Each scan is organised like a depth image: points in the camera frame (z forward, x right, y down),
 * NaN where the ray leaves through the window or exceeds the range, and the camera pose in the map frame
 * in sensor_origin_ / sensor_orientation_, as PCL's grabbers and PCD VIEWPOINT do it.
 */
std::vector<SceneCloud::Ptr> scanSyntheticRoom();

/**
 * Frame `index` (0, 1 or 2) of a 320×240 depth camera moving a few centimetres between frames through the
 * room: organised, NaN pixels (about a tenth) where nothing is in range, points in the camera frame and the
 * VIEWPOINT a depth-camera driver writes (origin zero, a half turn about x), as PCL's Kinect captures are.
 */
SceneCloud::Ptr syntheticDepthFrame(int index);

/**
 * Sweep `index` (0 or 1) of a spinning laser scanner in the room: unorganised, about 57,000 points with a few
 * exact duplicates, the sensor at the origin of its scan. Scan 1 placed by laserScanPose(1) lands on scan 0.
 */
SceneCloud::Ptr syntheticLaserScan(int index);

/**
 * Where laser scan `index` lies in scan 0's frame: a turn of 0.72 rad about z and (1.83, 0.69, 0), a few
 * centimetres and degrees from the guess PCL's NDT tutorial starts the real pair from.
 */
Eigen::Affine3f laserScanPose(int index);

/**
 * Airborne laser points over 134 m × 302 m of hills, buildings and trees in UTM coordinates (x about 5.1e5,
 * y about 5.4e6): unorganised, no sensor pose, a crowded strip where two flight lines overlap.
 */
SceneCloud::Ptr syntheticAirborneTerrain();

/**
 * The project's stand-in for one of the real scans the tests read (doc/user_guide.md lists them), by its
 * file name: kinect_capture000{1,2,3}.pcd, room_scan{1,2}.pcd, terrain_samp11.pcd. Throws for other names.
 */
SceneCloud::Ptr syntheticTwin(const std::string& real_scan_name);

}  // namespace fot_tools
