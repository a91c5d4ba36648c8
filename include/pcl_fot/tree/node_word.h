#pragma once

#include <cstddef>
#include <cstdint>

#include <pcl_fot/tree/key.h>

namespace pcl {
namespace fot {

/**
 * One FastOctTree node: a single 32-bit word (paper §II).
 *
 * Tag bit 0 set: a bitmap word. Bits 16..31 hold the states of the node's 8 octants, 2 bits each
 * (octant i at bits 16+2i), and bits 2..15 are zero. At level 1 the octants are voxels: the paper's
 * FOT leaf. Above level 1 each octant is a uniform region. Bit 1 (kValueFlag) marks a word whose known
 * cells carry log-odds between the clamps (see LeafValues): bits 2..15 then hold the index of their one
 * value in the tree's palette, when all its known cells hold one value; or, at level 1 only, kByteRow when
 * the tree keeps the 8 cells' palette indices in a row of bytes aside, or 0 when it keeps their 8 floats in
 * a row aside. Above level 1 a flagged word's known octants are cubes of its one value, as OctoMap prunes
 * equal values. Its states are the values thresholded, so a reader of states needs no values. Tag bit 0
 * clear: a reference, the index of the pool block that holds the 8 child words.
 */
using NodeWord = std::uint32_t;
static_assert(sizeof(NodeWord) == 4, "a FastOctTree node is exactly one 32-bit word");

namespace node {

constexpr NodeWord kBitmapTag = 1u;
constexpr NodeWord kValueFlag = 2u;
constexpr unsigned kPaletteShift = 2;
constexpr NodeWord kPaletteMask = 0x3FFFu << kPaletteShift;
constexpr std::uint32_t kByteRow = 0x3FFFu;
constexpr unsigned kStateShift = 16;
/** Largest block index a reference word can hold. */
constexpr std::uint32_t kMaxBlocks = 0x7FFFFFFFu;

constexpr bool isBitmap(NodeWord w) {
  return (w & kBitmapTag) != 0;
}
/** A leaf whose cells carry values: never uniform, so it never folds into its parent. */
constexpr bool hasValues(NodeWord w) {
  return (w & (kBitmapTag | kValueFlag)) == (kBitmapTag | kValueFlag);
}
constexpr NodeWord reference(std::uint32_t block) {
  return block << 1;
}
constexpr std::uint32_t block(NodeWord w) {
  return w >> 1;
}
/** Pool offset of a reference's first child word. */
constexpr std::size_t childBase(NodeWord w) {
  return std::size_t(w >> 1) * 8;
}
/** Pool offset of a reference's child o. */
constexpr std::size_t childOffset(NodeWord w, unsigned o) {
  return childBase(w) + o;
}

constexpr CellState state(NodeWord w, unsigned octant) {
  return CellState((w >> (kStateShift + 2 * octant)) & 3u);
}

constexpr NodeWord withState(NodeWord w, unsigned octant, CellState s) {
  const unsigned shift = kStateShift + 2 * octant;
  return (w & ~(3u << shift)) | (NodeWord(s) << shift);
}

/** Sets the octants `mask` selects (bit i: octant i) to `s`. */
constexpr NodeWord withStates(NodeWord w, std::uint32_t mask, CellState s) {
  std::uint32_t pairs = mask & 0xFFu;  // spread bit i to bit 2i
  pairs = (pairs | (pairs << 4)) & 0x0F0Fu;
  pairs = (pairs | (pairs << 2)) & 0x3333u;
  pairs = (pairs | (pairs << 1)) & 0x5555u;
  const NodeWord field = (pairs * 3u) << kStateShift;
  return (w & ~field) | ((pairs * NodeWord(s)) << kStateShift);
}

/** A flagged word's palette index; 0 when its values are in a row of floats. */
constexpr std::uint32_t palette(NodeWord w) {
  return (w & kPaletteMask) >> kPaletteShift;
}
/** A flagged leaf whose values are in a row, of floats or of palette indices. */
constexpr bool hasValueRow(NodeWord w) {
  return hasValues(w) && (palette(w) == 0 || palette(w) == kByteRow);
}

/** A flagged word whose 8 octants hold one known state and one palette value: a cube of that value. */
constexpr bool isValueUniform(NodeWord w) {
  const NodeWord states = w >> kStateShift;
  const std::uint32_t p = palette(w);
  return hasValues(w) && p != 0 && p != kByteRow && (states & 3u) != 0 && states == (states & 3u) * 0x5555u;
}

/** Bits set in an octant mask. Without -mpopcnt the builtin is a libgcc call, so count in registers. */
constexpr unsigned popcount(std::uint32_t mask) {
  std::uint32_t x = mask & 0xFFu;
  x = x - ((x >> 1) & 0x55u);
  x = (x & 0x33u) + ((x >> 2) & 0x33u);
  return unsigned((x + (x >> 4)) & 0x0Fu);
}

/** Cells in `count` cubes of 2^level cells per axis: count · 8^level, saturating instead of overflowing. */
constexpr std::uint64_t cellsIn(std::uint64_t count, unsigned level) {
  if (count == 0) return 0;
  return level < 21 && count <= (~std::uint64_t(0) >> (3 * level)) ? count << (3 * level) : ~std::uint64_t(0);
}

/** A bitmap whose 8 octants all hold `s`. */
constexpr NodeWord uniform(CellState s) {
  return kBitmapTag | ((NodeWord(s) * 0x5555u) << kStateShift);
}

constexpr bool isUniform(NodeWord w) {
  const NodeWord states = w >> kStateShift;
  return (w & 0xFFFFu) == kBitmapTag && states == (states & 3u) * 0x5555u;
}

/**
 * Octant o of the bitmap word w above level 1 as a word one level down: uniform, or, in a flagged word, a
 * cube of its one value.
 */
constexpr NodeWord octantWord(NodeWord w, unsigned o) {
  const CellState s = state(w, o);
  return uniform(s) | (hasValues(w) && s != CellState::Unknown ? w & (kValueFlag | kPaletteMask) : 0u);
}

/** The state of a uniform bitmap. */
constexpr CellState uniformState(NodeWord w) {
  return CellState((w >> kStateShift) & 3u);
}

/** Gathers bits 0, 2, 4, .. 14 of x into bits 0..7. */
constexpr std::uint32_t compressEven(std::uint32_t x) {
  x &= 0x5555u;
  x = (x | (x >> 1)) & 0x3333u;
  x = (x | (x >> 2)) & 0x0F0Fu;
  return (x | (x >> 4)) & 0x00FFu;
}

/** 8-bit mask of the octants holding `s` (state 3 never occurs, so one bit of each pair decides). */
constexpr std::uint32_t octantMask(NodeWord w, CellState s) {
  const std::uint32_t states = w >> kStateShift;
  switch (s) {
    case CellState::Occupied:
      return compressEven(states >> 1);
    case CellState::Free:
      return compressEven(states);
    default:
      return ~(compressEven(states >> 1) | compressEven(states)) & 0xFFu;
  }
}

/** The state bits of a bitmap word that mark Occupied or Free octants: one bit of every pair. */
constexpr NodeWord stateBits(CellState s) {
  return (s == CellState::Occupied ? 0xAAAAu : s == CellState::Free ? 0x5555u : 0u) << kStateShift;
}

/**
 * Whether any octant of a bitmap word holds `s`. Occupied (binary 10) and free (01) are each one bit of
 * every pair, so for them this is a single test, where the searches ask it of every child they pass.
 */
constexpr bool holds(NodeWord w, CellState s) {
  return s == CellState::Unknown ? octantMask(w, s) != 0 : (w & stateBits(s)) != 0;
}

}  // namespace node
}  // namespace fot
}  // namespace pcl
