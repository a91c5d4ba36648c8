#pragma once

#include <cstdint>
#include <limits>

#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

struct PsiOptions {
  /** Compare free cells as well as occupied ones (the paper's V = {occupied, free}). */
  bool include_free = false;
  /** Each cell's distance counts at most this many cells: a robust score for registration. */
  std::int64_t cap = std::numeric_limits<std::int64_t>::max();
  /**
   * Worker threads; 0 takes every hardware thread, and at most four per hardware thread are used. A thread
   * is only started for every 128 pieces of work (16³ bricks, or lone cells), so small maps run on one. The
   * result does not depend on it.
   */
  unsigned threads = 1;
};

/**
 * The map similarity ψ of Poppinga et al. (§IV, eqs. 1–2): over the values compared, the sum of every
 * cell's Manhattan distance, in cells, to the nearest cell of the other map with the same value, taken in
 * both directions. Zero for equal maps; symmetric.
 */
struct PsiResult {
  std::uint64_t sum = 0;    ///< ψ in cells (with the cap, if any)
  std::uint64_t cells = 0;  ///< cells that contributed, of both maps
  /**
   * False when, for some value, one map has cells and the other none, so those distances do not exist:
   * sum then holds only the parts that do. With a cap every such cell counts the cap, and ψ is defined.
   */
  bool defined = true;
  double resolution = 0;  ///< metres per cell

  /** The mean distance per contributing cell, in cells; 0 when no cell contributed. */
  double mean() const { return cells ? double(sum) / double(cells) : 0.0; }
  double metres() const { return double(sum) * resolution; }
  double meanMetres() const { return mean() * resolution; }
};

/**
 * ψ(a, b) with the nearest-tree-neighbour search: a's cells are visited in Morton order, so each search
 * starts where the last one ended, and a uniform region of a that b holds the same way everywhere
 * counts zero without being expanded. Exact: it equals brute force and the dmap_v method to the cell.
 * Throws std::invalid_argument when the maps do not share their voxel grid (resolution and origin).
 */
PsiResult psi(const FastOctTree& a, const FastOctTree& b, const PsiOptions& options = {});

}  // namespace fot
}  // namespace pcl
