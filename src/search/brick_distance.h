#pragma once
// Private to the library: ψ's exact Manhattan distances for a brick of cells at a time, by bit dilation.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <pcl_fot/detail/bits.h>
#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace detail {

/** Side³ cells, one bit each: cell (x, y, z) is bit x + Side·(y + Side·z), so a row along x is Side bits. */
template <unsigned Side>
struct BitCube {
  static_assert(Side == 8 || Side == 16, "a row must divide a 64-bit word");
  static constexpr unsigned kSide = Side;
  static constexpr unsigned kWords = Side * Side * Side / 64;
  static constexpr unsigned kRowsPerWord = 64 / Side;

  std::array<std::uint64_t, kWords> bits{};

  std::uint64_t row(unsigned y, unsigned z) const {
    const unsigned i = Side * (y + Side * z);
    return (bits[i >> 6] >> (i & 63)) & ((std::uint64_t(1) << Side) - 1);
  }
  void orRow(unsigned y, unsigned z, std::uint64_t row_bits) {
    const unsigned i = Side * (y + Side * z);
    bits[i >> 6] |= row_bits << (i & 63);
  }
  bool any() const {
    std::uint64_t a = 0;
    for (std::uint64_t w : bits) a |= w;
    return a != 0;
  }
  unsigned count() const {
    unsigned n = 0;
    for (std::uint64_t w : bits)
      if (w) n += popcount64(w);  // most words of a sparse brick are empty
    return n;
  }

  /** Sets the cube of `side` cells per axis whose lowest corner is (x, y, z). */
  void setCube(unsigned x, unsigned y, unsigned z, unsigned side) {
    const std::uint64_t row_bits = (side >= 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << side) - 1) << x;
    for (unsigned k = 0; k < side; ++k)
      for (unsigned j = 0; j < side; ++j) orRow(y + j, z + k, row_bits);
  }

  /**
   * Sets the cells holding `state` below the level-`level` word `w`, whose corner is cell (x, y, z) of
   * this cube.
   */
  void setFromWord(const NodeWord* words, NodeWord w, unsigned level, unsigned x, unsigned y, unsigned z,
                   CellState state) {
    if (level == 1) {  // the leaf: octant bit 0 is x, so each pair of octants is one row's two cells
      const std::uint32_t m = node::octantMask(w, state);
      orRow(y, z, std::uint64_t(m & 3u) << x);
      orRow(y + 1, z, std::uint64_t((m >> 2) & 3u) << x);
      orRow(y, z + 1, std::uint64_t((m >> 4) & 3u) << x);
      orRow(y + 1, z + 1, std::uint64_t((m >> 6) & 3u) << x);
      return;
    }
    const unsigned sub = level - 1;
    auto at = [&](unsigned o, unsigned axis, unsigned c) {
      return c + tree_coord::childOffset(o, axis, sub);
    };
    if (node::isBitmap(w)) {
      for (std::uint32_t m = node::octantMask(w, state); m; m &= m - 1) {
        const unsigned o = detail::lowestBit(m);
        setCube(at(o, 0, x), at(o, 1, y), at(o, 2, z), 1u << sub);
      }
      return;
    }
    for (unsigned o = 0; o < 8; ++o) {
      const NodeWord child = words[node::childOffset(w, o)];
      if (node::isBitmap(child) && !node::holds(child, state)) continue;  // most, in sparse maps
      setFromWord(words, child, sub, at(o, 0, x), at(o, 1, y), at(o, 2, z), state);
    }
  }
};

/**
 * A tree's cells of one state, read as aligned 8³ bit parts through a ConstAccessor (LineBurstAccess)
 * and cached: neighbouring windows share most of their parts.
 */
class PartCache {
 public:
  using Part = BitCube<8>;

  PartCache(const FastOctTree& tree, CellState state);
  /**
   * The part whose lowest corner is (x, y, z), in tree coordinates, multiples of 8: its words, slice z in
   * word z and row y in byte y; nullptr if it holds no cell.
   */
  const std::uint64_t* part(std::uint32_t x, std::uint32_t y, std::uint32_t z);

 private:
  static constexpr std::size_t kMaxSlots = 4096;
  /** Which part a slot holds. Only the tags start zeroed (no part): a slot's words are written when read. */
  enum class Held : std::uint8_t { Nothing, EmptyPart, Cells };
  struct Tag {
    std::uint32_t corner[3];
    Held held;
  };

  void read(std::uint32_t x, std::uint32_t y, std::uint32_t z, Part& out);

  const FastOctTree& tree_;
  CellState state_;
  ConstAccessor cells_;
  std::size_t mask_;  // slots - 1: a power of two, as a small tree needs fewer, so the slot is a mask
  std::vector<Tag> tags_;
  std::unique_ptr<std::uint64_t[]> words_;  // Part::kWords per slot
};

/** The cells of an aligned 16³ brick: one level-4 node. */
constexpr unsigned kBrickLevel = 4;
using Brick = BitCube<1u << kBrickLevel>;

/**
 * Exact Manhattan distances, up to Reach cells, from the cells of a brick to the nearest cell of a tree.
 * The tree's cells in the window reaching Reach cells beyond the brick are read into bit rows. Dilating
 * them by the unit L1 ball (a cell and its six face neighbours) adds the cells one step further, so after
 * d dilations the brick's cells that meet the set are exactly those at distance d. Integer work on rows
 * of bits, with no search: the cost is per brick, not per cell.
 */
template <unsigned Reach>
class BrickWindow {
 public:
  static constexpr unsigned kSide = 1u << kBrickLevel;
  static constexpr unsigned kWindow = kSide + 2 * Reach;
  static_assert(Reach % 8 == 0 && kWindow <= 64, "the window is made of whole parts, a row of one word");
  using Row = typename std::conditional<kWindow <= 32, std::uint32_t, std::uint64_t>::type;

  BrickWindow() : rows_(3 * kWindow * kWindow) {}

  /**
   * Settles the cells of `cells`, the brick whose lowest corner is `corner` (tree coordinates), that lie
   * between `from` and `last` (at most Reach) cells from the tree's: removes them from `cells` and calls
   * met(d, w, bits) with the bits of brick word w found at distance d. The cells left are further than
   * `last`. Afterwards holds() answers for the window.
   */
  template <typename Met>
  void settle(PartCache& parts, const std::uint32_t corner[3], Brick& cells, unsigned from, unsigned last,
              Met&& met) {
    const std::uint32_t lo[3] = {corner[0] - Reach, corner[1] - Reach, corner[2] - Reach};
    if (!load(parts, lo)) return;
    for (unsigned d = 0; d <= last && cells.any(); ++d) {
      const Row* r = d == 0 ? rows(kTargets) : dilate(d);
      if (d >= from) take(r, d, cells, met);
    }
  }

  /** Whether the tree holds the cell at (x, y, z), in window coordinates: Reach + the brick's own. */
  bool holds(unsigned x, unsigned y, unsigned z) const {
    return (rows_[kTargets * kWindow * kWindow + z * kWindow + y] >> x) & 1u;
  }

 private:
  static constexpr unsigned kTargets = 2;  // the buffer holding the tree's cells; 0 and 1 hold dilations

  Row* rows(unsigned buffer) { return rows_.data() + buffer * kWindow * kWindow; }
  /** Reads the window whose lowest corner is `lo`; false if the tree has no cell in it. */
  bool load(PartCache& parts, const std::uint32_t lo[3]);
  /** Dilates once more, to step `step`, and returns the rows; only those later steps still read are
   * computed. */
  const Row* dilate(unsigned step);

  template <typename Met>
  void take(const Row* r, unsigned d, Brick& cells, Met& met) {
    for (unsigned w = 0; w < Brick::kWords; ++w) {
      if (!cells.bits[w]) continue;
      std::uint64_t near = 0;
      for (unsigned q = 0; q < Brick::kRowsPerWord; ++q) {
        const unsigned row = w * Brick::kRowsPerWord + q, y = row % kSide, z = row / kSide;
        near |= std::uint64_t((r[(Reach + z) * kWindow + Reach + y] >> Reach) & 0xFFFFu) << (kSide * q);
      }
      const std::uint64_t hit = cells.bits[w] & near;
      if (!hit) continue;
      cells.bits[w] &= ~hit;
      met(d, w, hit);
    }
  }

  std::vector<Row> rows_;  // three buffers of kWindow × kWindow rows, [z][y], bit x
};

/**
 * Settles a brick's cells with windows: within 8 cells, then, for the cells left of a brick still dense
 * enough, within 16. Sparser bricks cost less cell by cell, with the nearest-tree-neighbour search.
 */
class BrickSettler {
 public:
  /** Below this many cells a window costs more than searching each cell. */
  static constexpr unsigned kMinNearCells = 4, kMinFarCells = 24;
  static constexpr unsigned kNearReach = 8, kFarReach = 16;

  BrickSettler(const FastOctTree& tree, CellState state) : parts_(tree, state) {}

  /**
   * BrickWindow::settle up to `limit` cells away (with the far window only beyond 8). Returns the distance
   * within which every cell of the brick was settled (the cells left are further), or -1 if none was tried.
   */
  template <typename Met>
  std::int64_t settle(const std::uint32_t corner[3], Brick& cells, std::int64_t limit, Met&& met) {
    if (limit < 0 || cells.count() < kMinNearCells) return -1;
    std::copy(corner, corner + 3, corner_);
    const unsigned near = unsigned(std::min<std::int64_t>(limit, kNearReach));
    near_.settle(parts_, corner, cells, 0, near, met);
    if (limit <= kNearReach || cells.count() < kMinFarCells) return near;
    const unsigned far = unsigned(std::min<std::int64_t>(limit, kFarReach));
    far_.settle(parts_, corner, cells, kNearReach + 1, far, met);
    return far;
  }

  /**
   * The cell of the tree nearest to cell (x, y, z) of the brick last settled, which settle() found at
   * distance d: of all at that distance, the one with the smallest x, then y, then z (tree coordinates).
   */
  void nearestAt(unsigned x, unsigned y, unsigned z, unsigned d, std::uint32_t out[3]) const {
    if (d <= kNearReach)
      find(near_, kNearReach, x, y, z, d, out);
    else
      find(far_, kFarReach, x, y, z, d, out);
  }

 private:
  template <typename Window>
  void find(const Window& w, unsigned reach, unsigned x, unsigned y, unsigned z, unsigned d,
            std::uint32_t out[3]) const {
    const int c[3] = {int(reach + x), int(reach + y), int(reach + z)}, r = int(d);
    // The L1 sphere of radius d, in key order; the first cell held is the answer.
    for (int dx = -r; dx <= r; ++dx) {
      const int ry = r - std::abs(dx);
      for (int dy = -ry; dy <= ry; ++dy) {
        const int rz = ry - std::abs(dy);
        for (int dz : {-rz, rz}) {
          if (w.holds(unsigned(c[0] + dx), unsigned(c[1] + dy), unsigned(c[2] + dz))) {
            out[0] = corner_[0] + x + dx, out[1] = corner_[1] + y + dy, out[2] = corner_[2] + z + dz;
            return;
          }
          if (rz == 0) break;
        }
      }
    }
    throw std::logic_error("pcl::fot: a settled cell has no neighbour at its distance");
  }

  PartCache parts_;
  BrickWindow<kNearReach> near_;
  BrickWindow<kFarReach> far_;
  std::uint32_t corner_[3] = {0, 0, 0};
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
