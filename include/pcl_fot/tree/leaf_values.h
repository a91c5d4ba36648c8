#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include <pcl_fot/detail/row_pages.h>
#include <pcl_fot/tree/node_word.h>

namespace pcl {
namespace fot {

/** Thrown when an operation would grow the pool beyond the cap set with setMaxMemoryBytes(). */
class MemoryLimitError : public std::length_error {
 public:
  using std::length_error::length_error;
};

/**
 * The log-odds of a FastOctTree's flagged words, whose known cells lie between the clamps (node_word.h).
 * A word whose known cells share one value names it in the palette (up to 16382 values, in the word): a
 * leaf, or a word above the leaves whose octants are cubes of that value. Any other flagged leaf has a row of
 * 8 values aside: 8 palette indices (bytes) when the palette's first 255 values hold them, else 8 floats. A
 * row is found through an index parallel to the tree's pool, by the leaf word's offset, which exists only
 * while some leaf has a row.
 *
 * The tree owns the words and calls these with a leaf's word and offset; it tells the index when its pool
 * grows, shrinks or moves blocks.
 */
class LeafValues {
 public:
  /** The tree's pool, for the memory cap: its words in use, its capacity, and the cap. */
  struct Pool {
    std::size_t words, capacity, max_bytes;
  };

  /** The value of known octant o of the flagged word `w` at pool offset `at`. */
  float value(NodeWord w, std::size_t at, unsigned o) const {
    const std::uint32_t p = node::palette(w);
    if (p == 0) return float_rows_.at(row_of_[at])[o];
    return palette_[p == node::kByteRow ? byte_rows_.at(row_of_[at])[o] : p];
  }
  /** All 8 values of the flagged word `w` at `at`; NaN for its unknown cells. */
  void values(NodeWord w, std::size_t at, float (&v)[8]) const;

  /**
   * Stores `v` (NaN: unknown) for the leaf at `at`, whose word was `old`: in the palette if its known cells
   * hold one value and the palette has room, else in a row. Returns `states` flagged accordingly. Throws
   * MemoryLimitError, before anything changes, if a new row would take the pool beyond its cap.
   */
  NodeWord store(std::size_t at, NodeWord old, NodeWord states, const float (&v)[8], const Pool& pool);
  /**
   * `states` flagged as holding `value`, unsettled, in every known octant: a word above the leaves whose
   * octants are cubes of one value (node::octantWord). 0 when the palette is full.
   */
  NodeWord named(NodeWord states, float value) {
    const std::uint32_t p = paletteIndex(value);
    return p == 0 ? 0 : states | node::kValueFlag | (p << node::kPaletteShift);
  }
  /** Frees the row of the leaf word `w` at `at`, if it has one. */
  void release(NodeWord w, std::size_t at);
  /** Frees every row; the palette stays. */
  void releaseRows();
  /** Frees every row and empties the palette. */
  void clear();
  /**
   * Makes room for one more row once the pool has grown by `extra_words` (an expansion about to happen), or
   * throws MemoryLimitError before anything changes.
   */
  void reserveRow(const Pool& pool, std::size_t extra_words = 0);

  /** Whether the index parallel to the pool exists: the pool then costs twice its words. */
  bool indexed() const { return !row_of_.empty(); }
  /** The pool now has `words` words. */
  void poolResized(std::size_t words) {
    if (indexed()) row_of_.resize(words);
  }
  /** The pool has room for `capacity` words. */
  void poolReserved(std::size_t capacity) {
    if (indexed()) row_of_.reserve(capacity);
  }
  /** The leaf words at offsets from .. from + n - 1 moved to to .. to + n - 1. */
  void poolMoved(std::size_t from, std::size_t to, std::size_t n) {
    if (indexed())
      std::copy_n(row_of_.begin() + std::ptrdiff_t(from), n, row_of_.begin() + std::ptrdiff_t(to));
  }
  /** Gives back the room kept for growth; with `palette_unused` (no flagged leaf), the palette too. */
  void shrinkToFit(bool palette_unused);

  std::size_t rowCount() const { return float_rows_.live() + byte_rows_.live(); }
  /** The rows' bytes, free rows and pages included. */
  std::size_t rowBytes() const { return float_rows_.bytes() + byte_rows_.bytes(); }
  /** Every byte held beyond the object: the index, the rows and the palette. */
  std::size_t bytes() const {
    return row_of_.capacity() * sizeof(std::uint32_t) + rowBytes() +
           palette_.capacity() * (sizeof(float) + 2 * sizeof(void*));
  }

 private:
  /** The palette index of a value, added if new; 0 when the palette is full. */
  std::uint32_t paletteIndex(float value);

  std::vector<std::uint32_t> row_of_;  // by pool offset: the row of a flagged leaf word there
  detail::RowPages<float, 8> float_rows_;
  detail::RowPages<std::uint8_t, 8> byte_rows_;
  // The values leaves name; entry 0 is unused. Only ever grows, up to 16382 values.
  std::vector<float> palette_;
  std::unordered_map<std::uint32_t, std::uint32_t> palette_of_;  // a value's bits -> its index
  struct PaletteHit {
    std::uint32_t bits = 0, index = 0;  // index 0: empty
  };
  static constexpr unsigned kPaletteHitBits = 6;
  std::array<PaletteHit, std::size_t(1) << kPaletteHitBits> palette_hits_{};
};

}  // namespace fot
}  // namespace pcl
