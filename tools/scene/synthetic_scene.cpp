#include "synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <Eigen/Geometry>

namespace fot_tools {
namespace {

constexpr float kNoHit = std::numeric_limits<float>::infinity();

struct Box {
  Eigen::Vector3f lo, hi;
};

/** Nearest t > 0 where o + t d enters the box, or kNoHit (slab method). */
float hitBox(const Eigen::Vector3f& o, const Eigen::Vector3f& d, const Box& b) {
  float t0 = 0.0f, t1 = kNoHit;
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.0f / d[a];
    float ta = (b.lo[a] - o[a]) * inv, tb = (b.hi[a] - o[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return (t0 <= t1 && t0 > 1e-4f) ? t0 : kNoHit;
}

float hitSphere(const Eigen::Vector3f& o, const Eigen::Vector3f& d, const Eigen::Vector3f& c, float r) {
  const Eigen::Vector3f oc = o - c;
  const float b = oc.dot(d), disc = b * b - (oc.squaredNorm() - r * r);
  if (disc < 0) return kNoHit;
  const float t = -b - std::sqrt(disc);
  return t > 1e-4f ? t : kNoHit;
}

/** A vertical cylinder standing on the floor. */
float hitPillar(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float cx, float cy, float r, float h) {
  const float dx = o.x() - cx, dy = o.y() - cy;
  const float a = d.x() * d.x() + d.y() * d.y(), b = dx * d.x() + dy * d.y(), c = dx * dx + dy * dy - r * r;
  const float disc = b * b - a * c;
  if (a < 1e-12f || disc < 0) return kNoHit;
  const float t = (-b - std::sqrt(disc)) / a, z = o.z() + t * d.z();
  return (t > 1e-4f && z >= 0 && z <= h) ? t : kNoHit;
}

/** Distance to the first surface of the room along a unit ray, or kNoHit. */
float castScene(const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
  // The room's inside: leave through the nearest wall, unless that spot is the open window.
  const Eigen::Vector3f lo(-4.0f, -3.0f, 0.0f), hi(4.0f, 3.0f, 3.0f);
  float t = kNoHit;
  for (int a = 0; a < 3; ++a) {
    if (d[a] > 0) t = std::min(t, (hi[a] - o[a]) / d[a]);
    if (d[a] < 0) t = std::min(t, (lo[a] - o[a]) / d[a]);
  }
  const Eigen::Vector3f exit = o + t * d;
  if (exit.x() > 3.999f && std::abs(exit.y()) < 1.0f && exit.z() > 1.0f && exit.z() < 2.2f) t = kNoHit;
  static const Box furniture[] = {{{0.5f, -0.8f, 0.0f}, {1.7f, 0.4f, 0.75f}},   // table
                                  {{-3.9f, 1.5f, 0.0f}, {-3.3f, 2.9f, 2.0f}},   // cabinet
                                  {{-0.6f, 2.2f, 0.0f}, {1.8f, 2.95f, 0.45f}},  // bench
                                  {{2.2f, 1.6f, 0.0f}, {3.0f, 2.4f, 1.1f}}};    // crate
  for (const Box& b : furniture) t = std::min(t, hitBox(o, d, b));
  t = std::min(t, hitSphere(o, d, Eigen::Vector3f(-1.0f, -1.6f, 0.5f), 0.5f));
  t = std::min(t, hitPillar(o, d, 2.6f, -1.4f, 0.25f, 3.0f));
  return t;
}

struct Pose {
  Eigen::Vector3f position;
  float yaw, pitch;  // radians; pitch > 0 looks down
};

SceneCloud::Ptr scanFrom(const Pose& pose, int width, int height, float focal, float max_range) {
  // Camera axes in the map frame: z forward, x right, y down.
  const Eigen::Vector3f forward(std::cos(pose.yaw) * std::cos(pose.pitch),
                                std::sin(pose.yaw) * std::cos(pose.pitch), -std::sin(pose.pitch));
  const Eigen::Vector3f right = forward.cross(Eigen::Vector3f::UnitZ()).normalized();
  const Eigen::Vector3f down = forward.cross(right);
  Eigen::Matrix3f camera_to_map;
  camera_to_map << right, down, forward;

  SceneCloud::Ptr cloud(new SceneCloud(width, height));
  cloud->is_dense = false;
  cloud->sensor_origin_ << pose.position, 0.0f;
  cloud->sensor_orientation_ = Eigen::Quaternionf(camera_to_map);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3f ray_cam =
          Eigen::Vector3f((u + 0.5f - width / 2.0f) / focal, (v + 0.5f - height / 2.0f) / focal, 1.0f);
      const Eigen::Vector3f dir = (camera_to_map * ray_cam).normalized();
      const float t = castScene(pose.position, dir);
      pcl::PointXYZ& p = cloud->at(u, v);
      if (t < max_range) {
        const Eigen::Vector3f hit_cam = ray_cam.normalized() * t;
        p.x = hit_cam.x();
        p.y = hit_cam.y();
        p.z = hit_cam.z();
      } else {
        p.x = p.y = p.z = nan;
      }
    }
  }
  return cloud;
}

/** The scene's ground in UTM metres: rolling hills, flat-roofed buildings and round tree crowns. */
double terrainHeight(double x, double y) {
  const double u = x - 512700.0, v = y - 5403548.0;
  double z = 330.0 + 25.0 * std::sin(u / 41.0) * std::cos(v / 57.0) + 0.08 * v;
  static const double buildings[][5] = {{20, 40, 45, 70, 12}, {80, 110, 150, 175, 9}, {30, 60, 220, 260, 15}};
  for (const auto& b : buildings)
    if (u >= b[0] && u <= b[1] && v >= b[2] && v <= b[3]) z += b[4];
  static const double trees[][3] = {{70, 30, 4}, {100, 90, 5}, {15, 130, 3.5}, {120, 270, 4.5}, {60, 200, 3}};
  for (const auto& t : trees) {
    const double r2 = ((u - t[0]) * (u - t[0]) + (v - t[1]) * (v - t[1])) / (t[2] * t[2]);
    if (r2 < 1.0) z += 2.0 * t[2] * std::sqrt(1.0 - r2);
  }
  return z;
}

}  // namespace

std::vector<SceneCloud::Ptr> scanSyntheticRoom() {
  const Pose poses[] = {{{-2.5f, -1.0f, 1.4f}, 0.25f, 0.20f}, {{2.5f, 1.0f, 1.6f}, 3.4f, 0.25f},
                        {{0.0f, -2.2f, 1.2f}, 1.57f, 0.15f},  {{-1.0f, 2.0f, 1.8f}, -1.2f, 0.45f},
                        {{1.5f, -0.2f, 2.4f}, 2.2f, 0.60f},   {{-3.0f, 0.5f, 1.0f}, -0.1f, 0.05f}};
  std::vector<SceneCloud::Ptr> scans;
  for (const Pose& pose : poses) scans.push_back(scanFrom(pose, 160, 120, 140.0f, 7.5f));
  return scans;
}

SceneCloud::Ptr syntheticDepthFrame(int index) {
  // Towards the furnished corner, the window at the left edge of the view: NaN there and beyond 5 m.
  const Pose pose{{0.6f + 0.04f * index, 0.0f + 0.02f * index, 1.6f}, 0.55f + 0.02f * index, 0.35f};
  SceneCloud::Ptr frame = scanFrom(pose, 320, 240, 262.5f, 5.0f);
  // A depth camera's driver reports points in its own frame, under a half turn about x.
  frame->sensor_origin_.setZero();
  frame->sensor_orientation_ = Eigen::Quaternionf(0.0f, 1.0f, 0.0f, 0.0f);
  return frame;
}

Eigen::Affine3f laserScanPose(int index) {
  if (index == 0) return Eigen::Affine3f::Identity();
  // Near the NDT tutorial's guess for the real pair, not on it: registration has work to do.
  return Eigen::Translation3f(1.83f, 0.69f, 0.0f) * Eigen::AngleAxisf(0.72f, Eigen::Vector3f::UnitZ());
}

SceneCloud::Ptr syntheticLaserScan(int index) {
  constexpr int kAzimuths = 720, kRows = 80;
  constexpr float kMaxRange = 20.0f, kPi = 3.14159265f;
  const Eigen::Vector3f first_position(-1.5f, -0.5f, 1.3f);
  const Eigen::Affine3f to_room = Eigen::Translation3f(first_position) * laserScanPose(index);
  SceneCloud::Ptr cloud(new SceneCloud);
  for (int a = 0; a < kAzimuths; ++a) {
    for (int r = 0; r < kRows; ++r) {
      const float azimuth = 2.0f * kPi * a / kAzimuths,
                  elevation = (-40.0f + 80.0f * r / (kRows - 1)) * kPi / 180;
      const Eigen::Vector3f dir(std::cos(elevation) * std::cos(azimuth),
                                std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      const float t = castScene(to_room.translation(), to_room.linear() * dir);
      if (t >= kMaxRange) continue;
      cloud->push_back(pcl::PointXYZ(t * dir.x(), t * dir.y(), t * dir.z()));
      // Scanners repeat a return now and then: exact duplicates.
      if ((a * kRows + r) % 499 == 0) cloud->push_back(cloud->back());
    }
  }
  return cloud;
}

SceneCloud::Ptr syntheticAirborneTerrain() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.45, 0.45);
  SceneCloud::Ptr cloud(new SceneCloud);
  const auto sample = [&](double x, double y) {
    cloud->push_back(pcl::PointXYZ(float(x), float(y), float(terrainHeight(x, y) + 0.05 * jitter(rng))));
  };
  for (double y = 5403548.2; y < 5403850.0; y += 1.3)
    for (double x = 512700.9; x < 512834.8; x += 1.3) sample(x + jitter(rng), y + jitter(rng));
  // Two flight lines overlap here: the strip holds twice the points.
  for (double y = 5403548.2; y < 5403850.0; y += 1.3)
    for (double x = 512760.0; x < 512780.0; x += 1.3) sample(x + jitter(rng), y + jitter(rng));
  return cloud;
}

SceneCloud::Ptr syntheticTwin(const std::string& name) {
  for (int i = 0; i < 3; ++i)
    if (name == "kinect_capture000" + std::to_string(i + 1) + ".pcd") return syntheticDepthFrame(i);
  for (int i = 0; i < 2; ++i)
    if (name == "room_scan" + std::to_string(i + 1) + ".pcd") return syntheticLaserScan(i);
  if (name == "terrain_samp11.pcd") return syntheticAirborneTerrain();
  throw std::invalid_argument("no synthetic twin of the scan '" + name + "'");
}

}  // namespace fot_tools
