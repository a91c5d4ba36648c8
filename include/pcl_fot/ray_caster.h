#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include <pcl_fot/key.h>

namespace pcl {
namespace fot {

/**
 * The 3D DDA of Amanatides & Woo over cell keys, shared by the tree and the dense grid.
 *
 * Its arithmetic is OctoMap's (computeRayKeys): a float direction normalised by a float length, double
 * crossing distances measured from the cell centre plus a float half cell, and ties between axes broken
 * towards y, then z. So for the same grid and endpoints both visit exactly the same cells. Coordinates
 * are relative to the grid origin.
 */
class RayWalker {
 public:
  /** Starts in cell `start`, which holds `origin`; `direction` is a unit vector. */
  RayWalker(const VoxelGrid& grid, const Key& start, const float origin[3], const float direction[3])
      : key_{start.x, start.y, start.z} {
    const double res = grid.resolution();
    for (int i = 0; i < 3; ++i) {
      step_[i] = direction[i] > 0.0f ? 1 : (direction[i] < 0.0f ? -1 : 0);
      if (step_[i] != 0) {
        const double border = (double(key_[i]) + 0.5) * res + double(float(step_[i] * res * 0.5));
        tmax_[i] = (border - double(origin[i])) / double(direction[i]);
        tdelta_[i] = res / std::fabs(double(direction[i]));
      } else {
        tmax_[i] = std::numeric_limits<double>::max();
        tdelta_[i] = std::numeric_limits<double>::max();
      }
    }
    next_ = nextAxis();
  }

  Key key() const { return Key{key_[0], key_[1], key_[2]}; }
  /** Distance along the ray at which it leaves the current cell. */
  double exitDistance() const { return tmax_[next_]; }

  /** Moves into the next cell. */
  void step() {
    key_[next_] += step_[next_];
    tmax_[next_] += tdelta_[next_];
    next_ = nextAxis();
  }

  bool at(const Key& k) const { return key_[0] == k.x && key_[1] == k.y && key_[2] == k.z; }

 private:
  unsigned nextAxis() const {  // OctoMap's order: x only if strictly first, ties go to y, then z
    const unsigned c = tmax_[0] < tmax_[1] ? 0u : 1u;
    return tmax_[c] < tmax_[2] ? c : 2u;
  }

  std::int32_t key_[3];
  int step_[3];
  double tmax_[3];
  double tdelta_[3];
  unsigned next_;
};

/** The ray from `from` towards `to` in grid-relative float coordinates: unit direction and length. */
struct RaySetup {
  float origin[3];
  float direction[3];
  float length;
};

/** Relative coordinates and OctoMap's float normalisation (its norm() sums float squares). */
inline RaySetup setupRay(const VoxelGrid& grid, const float from[3], const float to[3]) {
  RaySetup r;
  float d[3], o[3];
  for (int i = 0; i < 3; ++i) {
    o[i] = float(double(from[i]) - grid.origin()[i]);
    d[i] = float(double(to[i]) - grid.origin()[i]) - o[i];
  }
  r.length = float(std::sqrt(double(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])));
  for (int i = 0; i < 3; ++i) {
    r.origin[i] = o[i];
    r.direction[i] = d[i] / r.length;
  }
  return r;
}

/**
 * Visits every cell the segment from `origin` to `end` (map frame) passes: the origin's cell first, the
 * end's cell excluded, nothing if both are one cell. These are exactly the cells of OctoMap's
 * computeRayKeys. Returns false, visiting nothing, when an endpoint is not finite or beyond the key range.
 */
template <typename Visitor>
bool traceSegment(const VoxelGrid& grid, const float origin[3], const float end[3], Visitor&& visit) {
  Key from, to;
  if (!grid.pointToKey(origin[0], origin[1], origin[2], from) || !grid.pointToKey(end[0], end[1], end[2], to))
    return false;
  if (from == to) return true;
  visit(from);
  const RaySetup ray = setupRay(grid, origin, end);
  RayWalker walker(grid, from, ray.origin, ray.direction);
  // A DDA never takes more steps than the L1 distance of its end keys; the cap guards against a hang.
  std::int64_t budget = std::llabs(std::int64_t(to.x) - from.x) + std::llabs(std::int64_t(to.y) - from.y) +
                        std::llabs(std::int64_t(to.z) - from.z) + 3;
  while (--budget > 0) {
    walker.step();
    // Stop at the end cell, or where rounding made the walk miss it: past the segment's length.
    if (walker.at(to) || walker.exitDistance() > double(ray.length)) break;
    visit(walker.key());
  }
  return true;
}

}  // namespace fot
}  // namespace pcl
