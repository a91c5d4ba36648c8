#include "synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

pcl::PointCloud<pcl::PointXYZ>::Ptr scanFrom(const Pose& pose) {
  constexpr int kWidth = 160, kHeight = 120;
  constexpr float kFocal = 140.0f, kMaxRange = 7.5f;
  // Camera axes in the map frame: z forward, x right, y down.
  const Eigen::Vector3f forward(std::cos(pose.yaw) * std::cos(pose.pitch),
                                std::sin(pose.yaw) * std::cos(pose.pitch), -std::sin(pose.pitch));
  const Eigen::Vector3f right = forward.cross(Eigen::Vector3f::UnitZ()).normalized();
  const Eigen::Vector3f down = forward.cross(right);
  Eigen::Matrix3f camera_to_map;
  camera_to_map << right, down, forward;

  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>(kWidth, kHeight));
  cloud->is_dense = false;
  cloud->sensor_origin_ << pose.position, 0.0f;
  cloud->sensor_orientation_ = Eigen::Quaternionf(camera_to_map);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      const Eigen::Vector3f ray_cam =
          Eigen::Vector3f((u + 0.5f - kWidth / 2.0f) / kFocal, (v + 0.5f - kHeight / 2.0f) / kFocal, 1.0f);
      const Eigen::Vector3f dir = (camera_to_map * ray_cam).normalized();
      const float t = castScene(pose.position, dir);
      pcl::PointXYZ& p = cloud->at(u, v);
      if (t < kMaxRange) {
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

}  // namespace

std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr> scanSyntheticRoom() {
  const Pose poses[] = {{{-2.5f, -1.0f, 1.4f}, 0.25f, 0.20f}, {{2.5f, 1.0f, 1.6f}, 3.4f, 0.25f},
                        {{0.0f, -2.2f, 1.2f}, 1.57f, 0.15f},  {{-1.0f, 2.0f, 1.8f}, -1.2f, 0.45f},
                        {{1.5f, -0.2f, 2.4f}, 2.2f, 0.60f},   {{-3.0f, 0.5f, 1.0f}, -0.1f, 0.05f}};
  std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr> scans;
  for (const Pose& pose : poses) scans.push_back(scanFrom(pose));
  return scans;
}

}  // namespace fot_tools
