#pragma once

#include <cstdint>

#include <pcl_fot/detail/bits.h>
#include <pcl_fot/tree/key.h>

namespace pcl {
namespace fot {

/**
 * Tree coordinates: keys shifted by a constant, u = key + 0x2AAA8000. Nodes are aligned to multiples of
 * their size in this space, so the tree's shape depends only on its contents. The low 16 bits of the shift
 * put levels 1 to 16 on OctoMap's node boundaries (its key is key + 32768 on a grid with origin 0): the
 * level-16 node holding key 0 spans keys [-32768, 32767], OctoMap's root, and every OctoMap node is one node
 * here. Above level 16 the shift's alternating bits put the boundaries on alternating sides of that node,
 * so a map of s cells around it needs about log2(s) + 1 levels instead of the full depth.
 *
 * A level-l node spans 2^l cells per axis; its octant o (bit 0: x, bit 1: y, bit 2: z) is the child whose
 * cube holds the upper half along each axis whose bit is set. Every walk through the tree speaks this
 * vocabulary: the scalar functions for the hot loops that keep the axes in registers, TreeCoord elsewhere.
 */
namespace tree_coord {
constexpr std::uint32_t kShift = 0x2AAA8000u;

inline std::uint32_t fromKey(std::int32_t k) {
  return std::uint32_t(k) + kShift;
}
inline std::int32_t toKey(std::uint32_t u) {
  return std::int32_t(u - kShift);
}

/** Octant of the child of a level-`level` node that holds (x, y, z). */
inline unsigned octant(std::uint32_t x, std::uint32_t y, std::uint32_t z, unsigned level) {
  const unsigned b = level - 1;
  return ((x >> b) & 1u) | (((y >> b) & 1u) << 1) | (((z >> b) & 1u) << 2);
}

/** The offset, along `axis`, of octant o's cube from its parent's corner, for children of 2^child_level. */
inline std::uint32_t childOffset(unsigned o, unsigned axis, unsigned child_level) {
  return ((o >> axis) & 1u) << child_level;
}

/** The bits below `level`: a coordinate's offset inside its level-`level` node. */
inline std::uint32_t lowMask(unsigned level) {
  return std::uint32_t((std::uint64_t(1) << level) - 1);
}

/**
 * Lowest level (at least 1, the leaf word) whose nodes contain both coordinates, given their XORs.
 * Branch-free: consecutive accesses hit the same voxel unpredictably often.
 */
inline unsigned commonLevel(std::uint32_t dx, std::uint32_t dy, std::uint32_t dz) {
  return 1u + detail::highestBit(dx | dy | dz | 1u);
}
}  // namespace tree_coord

/** A cell, or a node's lowest corner, in tree coordinates. */
struct TreeCoord {
  std::uint32_t u[3] = {0, 0, 0};

  TreeCoord() = default;
  TreeCoord(std::uint32_t x, std::uint32_t y, std::uint32_t z) : u{x, y, z} {}
  explicit TreeCoord(const Key& k)
      : u{tree_coord::fromKey(k.x), tree_coord::fromKey(k.y), tree_coord::fromKey(k.z)} {}

  std::uint32_t operator[](unsigned axis) const { return u[axis]; }
  std::uint32_t& operator[](unsigned axis) { return u[axis]; }
  Key key() const { return Key{tree_coord::toKey(u[0]), tree_coord::toKey(u[1]), tree_coord::toKey(u[2])}; }

  /** Octant of the child of the level-`level` node holding this cell. */
  unsigned octant(unsigned level) const { return tree_coord::octant(u[0], u[1], u[2], level); }
  /** The lowest corner of the level-`level` node holding this cell. */
  TreeCoord corner(unsigned level) const {
    const std::uint32_t keep = ~tree_coord::lowMask(level);
    return TreeCoord(u[0] & keep, u[1] & keep, u[2] & keep);
  }
  /** This is a node's corner: the corner of its octant o, whose cube spans 2^child_level cells per axis. */
  TreeCoord child(unsigned o, unsigned child_level) const {
    return TreeCoord(u[0] + tree_coord::childOffset(o, 0, child_level),
                     u[1] + tree_coord::childOffset(o, 1, child_level),
                     u[2] + tree_coord::childOffset(o, 2, child_level));
  }
  /** Lowest level whose nodes hold both cells. */
  friend unsigned commonLevel(const TreeCoord& a, const TreeCoord& b) {
    return tree_coord::commonLevel(a[0] ^ b[0], a[1] ^ b[1], a[2] ^ b[2]);
  }
  friend bool operator==(const TreeCoord& a, const TreeCoord& b) {
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
  }
  friend bool operator!=(const TreeCoord& a, const TreeCoord& b) { return !(a == b); }
};

}  // namespace fot
}  // namespace pcl
