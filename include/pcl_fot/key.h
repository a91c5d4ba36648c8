#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

namespace pcl {
namespace fot {

/** The three states a cell can hold. The paper's binary map is the special case without Free. */
enum class CellState : std::uint8_t { Unknown = 0, Free = 1, Occupied = 2 };

/** Signed integer voxel coordinates relative to the map origin. */
struct Key {
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::int32_t z = 0;

  friend bool operator==(const Key& a, const Key& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
  friend bool operator!=(const Key& a, const Key& b) { return !(a == b); }
};

/** Keys must lie in [kMinKey, kMaxKey] on every axis; that is ±2^29 cells. */
constexpr std::int32_t kMinKey = -(1 << 29);
constexpr std::int32_t kMaxKey = (1 << 29) - 1;

/** Deepest possible root level: a level-l node spans 2^l cells per axis. */
constexpr unsigned kMaxLevel = 31;

inline bool isValidKey(const Key& k) {
  return k.x >= kMinKey && k.x <= kMaxKey && k.y >= kMinKey && k.y <= kMaxKey && k.z >= kMinKey &&
         k.z <= kMaxKey;
}

inline std::string toString(const Key& k) {
  return "(" + std::to_string(k.x) + ", " + std::to_string(k.y) + ", " + std::to_string(k.z) + ")";
}

struct KeyHash {
  std::size_t operator()(const Key& k) const {
    const std::uint64_t h = (std::uint64_t(std::uint32_t(k.x)) * 0x9E3779B97F4A7C15ull) ^
                            (std::uint64_t(std::uint32_t(k.y)) * 0xC2B2AE3D27D4EB4Full) ^
                            (std::uint64_t(std::uint32_t(k.z)) * 0x165667B19E3779F9ull);
    return std::size_t(h ^ (h >> 29));
  }
};

/**
 * Tree coordinates: keys shifted by a constant with alternating bits. Nodes are aligned to multiples of
 * their size in this space, so the tree's shape depends only on its contents. The shift keeps level
 * boundaries away from key 0, where sensors usually sit: a map spanning s cells around the origin needs
 * about log2(s) + 1 levels instead of the full depth.
 */
namespace tree_coord {
constexpr std::uint32_t kShift = 0x2AAAAAAAu;

inline std::uint32_t fromKey(std::int32_t k) {
  return std::uint32_t(k) + kShift;
}
inline std::int32_t toKey(std::uint32_t u) {
  return std::int32_t(u - kShift);
}

/** Octant (bit 0: x, bit 1: y, bit 2: z) of the child of a level-`level` node that holds (x, y, z). */
inline unsigned octant(std::uint32_t x, std::uint32_t y, std::uint32_t z, unsigned level) {
  const unsigned b = level - 1;
  return ((x >> b) & 1u) | (((y >> b) & 1u) << 1) | (((z >> b) & 1u) << 2);
}

/**
 * Lowest level (at least 1, the leaf word) whose nodes contain both coordinates, given their XORs.
 * Branch-free: consecutive accesses hit the same voxel unpredictably often.
 */
inline unsigned commonLevel(std::uint32_t dx, std::uint32_t dy, std::uint32_t dz) {
  return 32u - unsigned(__builtin_clz(dx | dy | dz | 1u));
}
}  // namespace tree_coord

/**
 * The voxel grid of a map: cell (i, j, k) spans [origin + i*res, origin + (i+1)*res) per axis.
 * Point-to-key conversion divides by the resolution exactly as pcl::octree does, so both agree on every
 * point when their grids share an origin.
 */
class VoxelGrid {
 public:
  explicit VoxelGrid(double resolution, double origin_x = 0.0, double origin_y = 0.0, double origin_z = 0.0)
      : resolution_(resolution), origin_{origin_x, origin_y, origin_z} {
    const std::string why = whyInvalid(resolution, origin_x, origin_y, origin_z);
    if (!why.empty()) throw std::invalid_argument("pcl::fot::VoxelGrid: " + why);
  }

  /**
   * Why no grid has this resolution and origin, or "" if one does. The resolution must be positive, and
   * every cell centre of the key range a finite float, as the points of a pcl::PointCloud are.
   */
  static std::string whyInvalid(double resolution, double origin_x, double origin_y, double origin_z) {
    char text[160];
    if (!(resolution > 0.0) || !std::isfinite(resolution)) {
      std::snprintf(text, sizeof(text), "the resolution must be positive and finite, got %g", resolution);
      return text;
    }
    const double reach = (double(kMaxKey) + 1.0) * resolution;
    for (double o : {origin_x, origin_y, origin_z})
      if (!(std::abs(o) + reach <= double(std::numeric_limits<float>::max()))) {
        std::snprintf(text, sizeof(text),
                      "resolution %g with origin (%g, %g, %g) puts cell centres beyond float's range",
                      resolution, origin_x, origin_y, origin_z);
        return text;
      }
    return {};
  }

  double resolution() const { return resolution_; }
  const double* origin() const { return origin_; }

  /** Converts one coordinate; false when it is not finite or lies outside the key range. */
  bool toKey(double c, unsigned axis, std::int32_t& k) const {
    const double q = (c - origin_[axis]) / resolution_;
    if (!(q >= double(kMinKey) && q < double(kMaxKey) + 1.0)) return false;  // also NaN and Inf
    const std::int32_t t = std::int32_t(q);
    k = t - std::int32_t(q < double(t));  // floor without a libm call
    return true;
  }

  /** False when the point is not finite or lies outside the representable range. */
  bool pointToKey(double x, double y, double z, Key& key) const {
    return toKey(x, 0, key.x) && toKey(y, 1, key.y) && toKey(z, 2, key.z);
  }

  /**
   * pointToKey for a point given singly: throws std::invalid_argument, naming `who`, when it is not finite;
   * false when it lies beyond the key range.
   */
  bool finitePointToKey(double x, double y, double z, Key& key, const char* who) const {
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
      throw std::invalid_argument(std::string(who) + ": the point is not finite");
    return pointToKey(x, y, z, key);
  }

  double keyToCoord(std::int32_t k, unsigned axis) const {
    return origin_[axis] + (double(k) + 0.5) * resolution_;
  }
  void keyToCenter(const Key& key, double& x, double& y, double& z) const {
    x = keyToCoord(key.x, 0);
    y = keyToCoord(key.y, 1);
    z = keyToCoord(key.z, 2);
  }

  friend bool operator==(const VoxelGrid& a, const VoxelGrid& b) {
    return a.resolution_ == b.resolution_ && a.origin_[0] == b.origin_[0] && a.origin_[1] == b.origin_[1] &&
           a.origin_[2] == b.origin_[2];
  }
  friend bool operator!=(const VoxelGrid& a, const VoxelGrid& b) { return !(a == b); }

 private:
  double resolution_;
  double origin_[3];
};

}  // namespace fot
}  // namespace pcl
