#pragma once
// Private to the library: ψ's exact Manhattan distances for a brick of cells at a time, by bit dilation.

#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include <pcl_fot/accessor.h>
#include <pcl_fot/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace detail {

/** Set bits of a 64-bit word, in registers (the builtin is a library call without -mpopcnt). */
inline unsigned popcount64(std::uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;
  return unsigned((x * 0x0101010101010101ull) >> 56);
}

/** Side³ cells, one bit each: cell (x, y, z) is bit x + Side·(y + Side·z), so a row along x is Side bits. */
template <unsigned Side>
struct BitCube {
  static_assert(Side == 8 || Side == 16, "a row must divide a 64-bit word");
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
    for (std::uint64_t w : bits) n += popcount64(w);
    return n;
  }

  /** Sets the cube of `side` cells per axis whose lowest corner is (x, y, z). */
  void setCube(unsigned x, unsigned y, unsigned z, unsigned side) {
    const std::uint64_t row_bits = (side >= 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << side) - 1) << x;
    for (unsigned k = 0; k < side; ++k)
      for (unsigned j = 0; j < side; ++j) orRow(y + j, z + k, row_bits);
  }

  /** Sets the cells holding `state` below the level-`level` word `w`, whose corner is (x, y, z). */
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
    const unsigned half = 1u << (level - 1);
    if (node::isBitmap(w)) {
      for (std::uint32_t m = node::octantMask(w, state); m; m &= m - 1) {
        const unsigned o = unsigned(__builtin_ctz(m));
        setCube(x + (o & 1u) * half, y + ((o >> 1) & 1u) * half, z + (o >> 2) * half, half);
      }
      return;
    }
    for (unsigned o = 0; o < 8; ++o)
      setFromWord(words, words[node::childBase(w) + o], level - 1, x + (o & 1u) * half,
                  y + ((o >> 1) & 1u) * half, z + (o >> 2) * half, state);
  }
};

/**
 * A tree's cells of one state, read as aligned 8³ bit parts through a ConstAccessor (LineBurstAccess)
 * and cached: neighbouring windows share most of their parts.
 */
class PartCache {
 public:
  using Part = BitCube<8>;
  struct Entry {
    std::uint32_t corner[3] = {0, 0, 0};
    bool valid = false;
    bool empty = true;
    Part part;
  };

  PartCache(const FastOctTree& tree, CellState state);
  /** The part whose lowest corner is (x, y, z), in tree coordinates, multiples of 8. */
  const Entry& part(std::uint32_t x, std::uint32_t y, std::uint32_t z);

 private:
  void read(std::uint32_t x, std::uint32_t y, std::uint32_t z, Entry& out);

  const FastOctTree& tree_;
  CellState state_;
  ConstAccessor cells_;
  std::vector<Entry> slots_;
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

  BrickWindow() : rows_(2 * kWindow * kWindow) {}

  /**
   * The sum of the distances of `cells`, the brick whose lowest corner is `corner` (tree coordinates),
   * each capped at `cap`, for the cells within Reach. Every cell is known to be at least `from` away.
   * Removes the cells it settled from `cells`: any left are further than Reach (and cap > Reach).
   */
  std::uint64_t settle(PartCache& parts, const std::uint32_t corner[3], Brick& cells, unsigned from,
                       std::int64_t cap);

 private:
  Row* rows(unsigned buffer) { return rows_.data() + buffer * kWindow * kWindow; }
  /** Reads the window whose lowest corner is `lo`; false if the tree has no cell in it. */
  bool load(PartCache& parts, const std::uint32_t lo[3]);
  /** Dilates once; only the rows that later steps still read are computed. */
  void dilate(unsigned step);
  /** Removes and counts the cells of `cells` that meet the current rows. */
  unsigned take(Brick& cells);

  std::vector<Row> rows_;  // two buffers of kWindow × kWindow rows, [z][y], bit x
  unsigned current_ = 0;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
