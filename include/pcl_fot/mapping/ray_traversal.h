#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include <pcl_fot/tree/cell_grid.h>
#include <pcl_fot/tree/key.h>

namespace pcl {
namespace fot {

/**
 * Where a DDA walk starts, per axis: the step (-1, 0 or 1), the distance along the ray at which it first
 * crosses a cell border, and the distance between crossings. Its arithmetic is OctoMap's (computeRayKeys):
 * double distances measured from the cell centre plus a float half cell, for a float direction normalised
 * by a float length.
 *
 * `start` is a cell the ray passes, distances are measured from `origin`, and `direction` is a unit vector.
 * With float coordinates the arithmetic is OctoMap's to the bit (its half cell is a float); with double
 * coordinates it is as exact as doubles allow, for callers that need no OctoMap parity.
 */
struct DdaStart {
  int step[3];
  double tmax[3];
  double tdelta[3];
};

template <typename Scalar>
DdaStart ddaStart(const CellGrid& grid, const Key& start, const Scalar origin[3], const Scalar direction[3]) {
  const double res = grid.resolution();
  const std::int32_t key[3] = {start.x, start.y, start.z};
  DdaStart s;
  for (int i = 0; i < 3; ++i) {
    s.step[i] = direction[i] > Scalar(0) ? 1 : (direction[i] < Scalar(0) ? -1 : 0);
    if (s.step[i] != 0) {
      const double border = (double(key[i]) + 0.5) * res + double(Scalar(s.step[i] * res * 0.5));
      s.tmax[i] = (border - double(origin[i])) / double(direction[i]);
      s.tdelta[i] = res / std::fabs(double(direction[i]));
    } else {
      s.tmax[i] = std::numeric_limits<double>::max();
      s.tdelta[i] = std::numeric_limits<double>::max();
    }
  }
  return s;
}

/**
 * The 3D DDA of Amanatides & Woo over cell keys, shared by the tree and the dense grid. Ties between axes
 * break towards y, then z, as in OctoMap, so for the same grid and endpoints both visit exactly the same
 * cells. Coordinates are relative to the grid origin.
 */
class RayWalker {
 public:
  /** Starts in cell `start`; see DdaStart for the arguments. */
  template <typename Scalar>
  RayWalker(const CellGrid& grid, const Key& start, const Scalar origin[3], const Scalar direction[3])
      : k0_(start.x), k1_(start.y), k2_(start.z) {
    const DdaStart s = ddaStart(grid, start, origin, direction);
    s0_ = s.step[0], s1_ = s.step[1], s2_ = s.step[2];
    t0_ = s.tmax[0], t1_ = s.tmax[1], t2_ = s.tmax[2];
    d0_ = s.tdelta[0], d1_ = s.tdelta[1], d2_ = s.tdelta[2];
  }

  Key key() const { return Key{k0_, k1_, k2_}; }
  /** Distance along the ray at which it leaves the current cell. */
  double exitDistance() const { return std::min(std::min(t0_, t1_), t2_); }

  /**
   * Moves into the next cell: across x only if x's crossing comes strictly first, ties go to y, then z
   * (OctoMap's order). Scalar fields and branches, not arrays: the walk stays in registers, and a ray's
   * regular axis pattern is what branch predictors learn best.
   */
  void step() {
    if (t0_ < t1_) {
      if (t0_ < t2_) {
        k0_ += s0_;
        t0_ += d0_;
      } else {
        k2_ += s2_;
        t2_ += d2_;
      }
    } else if (t1_ < t2_) {
      k1_ += s1_;
      t1_ += d1_;
    } else {
      k2_ += s2_;
      t2_ += d2_;
    }
  }

  bool at(const Key& k) const { return k0_ == k.x && k1_ == k.y && k2_ == k.z; }

 private:
  std::int32_t k0_, k1_, k2_;
  int s0_, s1_, s2_;
  double t0_, t1_, t2_;
  double d0_, d1_, d2_;
};

/** The ray from `from` towards `to` in grid-relative float coordinates: unit direction and length. */
struct RaySetup {
  float origin[3];
  float direction[3];
  float length;
};

/** Relative coordinates and OctoMap's float normalisation (its norm() sums float squares). */
inline RaySetup setupRay(const CellGrid& grid, const float from[3], const float to[3]) {
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
 * Walks the segment from `origin` to `end` (map frame) and hands its cells to `visit(const Key&)` in order:
 * the origin's cell first, the end's cell excluded, nothing if both are one cell. These are exactly the
 * cells of OctoMap's computeRayKeys. Returns how many cells the segment passes: 0 when both ends share a
 * cell, or an end is not finite or beyond the key range.
 */
template <typename Visitor>
std::size_t traceSegment(const CellGrid& grid, const float origin[3], const float end[3], Visitor&& visit) {
  Key from, to;
  if (!grid.pointToKey(origin[0], origin[1], origin[2], from) ||
      !grid.pointToKey(end[0], end[1], end[2], to) || from == to)
    return 0;
  const RaySetup ray = setupRay(grid, origin, end);
  RayWalker walker(grid, from, ray.origin, ray.direction);
  // The walk is monotone per axis, so it can only be at `to` after exactly `span` steps; a few more and
  // rounding has made it miss `to`, which the length test catches. The cap guards against a hang.
  const std::int64_t span = std::llabs(std::int64_t(to.x) - from.x) +
                            std::llabs(std::int64_t(to.y) - from.y) + std::llabs(std::int64_t(to.z) - from.z);
  const double length = ray.length;
  visit(from);
  std::size_t total = 1;
  for (std::int64_t steps = 1;; ++steps) {
    walker.step();
    if (steps >= span && (walker.at(to) || steps > span + 3)) break;
    if (walker.exitDistance() > length) break;  // rounding made the walk miss the end cell
    visit(walker.key());
    ++total;
  }
  return total;
}

}  // namespace fot
}  // namespace pcl
