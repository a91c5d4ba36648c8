#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include <pcl_fot/tree/key.h>

namespace pcl {
namespace fot {

/**
 * The cell grid of a map: cell (i, j, k) spans [origin + i*res, origin + (i+1)*res) per axis.
 * Point-to-key conversion divides by the resolution exactly as pcl::octree does, so both agree on every
 * point when their grids share an origin.
 */
class CellGrid {
 public:
  explicit CellGrid(double resolution, double origin_x = 0.0, double origin_y = 0.0, double origin_z = 0.0)
      : resolution_(resolution), origin_{origin_x, origin_y, origin_z} {
    const std::string why = whyInvalid(resolution, origin_x, origin_y, origin_z);
    if (!why.empty()) throw std::invalid_argument("pcl::fot::CellGrid: " + why);
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

  friend bool operator==(const CellGrid& a, const CellGrid& b) {
    return a.resolution_ == b.resolution_ && a.origin_[0] == b.origin_[0] && a.origin_[1] == b.origin_[1] &&
           a.origin_[2] == b.origin_[2];
  }
  friend bool operator!=(const CellGrid& a, const CellGrid& b) { return !(a == b); }

 private:
  double resolution_;
  double origin_[3];
};

}  // namespace fot
}  // namespace pcl
