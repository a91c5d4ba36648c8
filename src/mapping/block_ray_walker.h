#pragma once
// Private to the library: the scan insertion's ray walk, many rays at a time.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <pcl_fot/mapping/ray_traversal.h>
#include <pcl_fot/tree/cell_grid.h>
#include <pcl_fot/tree/key.h>
#include <pcl_fot/tree/tree_coord.h>

namespace pcl {
namespace fot {
namespace detail {

/**
 * The cells of a 4×4×4 block as a 64-bit mask: cell (x, y, z), each 0..3, is bit x + 4y + 16z. The lanes
 * compute that bit in a few operations; a leaf's eight cells, as the tree takes them, are gathered only
 * when a block is written.
 */
namespace block_cells {
inline unsigned bit(unsigned x, unsigned y, unsigned z) {
  return x + 4 * y + 16 * z;
}
/** The leaf (octant of the block's 2×2×2 leaves) holding the cell of `bit`. */
inline unsigned leafOf(unsigned bit) {
  return ((bit >> 1) & 1u) | ((bit >> 2) & 2u) | ((bit >> 3) & 4u);
}
/** The bits of a leaf's cells. */
inline std::uint64_t leafBits(unsigned leaf) {
  return std::uint64_t(0x330033) << (2 * (leaf & 1u) + 4 * (leaf & 2u) + 8 * (leaf & 4u));
}
/** The key of the cell of `bit` in the block (tree coordinates / 4). */
inline Key cellKey(const std::uint32_t (&block)[3], unsigned bit) {
  return TreeCoord(4 * block[0] + (bit & 3u), 4 * block[1] + (bit >> 2 & 3u), 4 * block[2] + (bit >> 4))
      .key();
}
/** The key of a leaf's lowest cell. */
inline Key leafKey(const std::uint32_t (&block)[3], unsigned leaf) {
  return TreeCoord(4 * block[0] + 2 * (leaf & 1u), 4 * block[1] + (leaf & 2u), 4 * block[2] + (leaf & 4u) / 2)
      .key();
}
/** A leaf's cells in `cells` as a leaf mask: bit o for the cell in octant o. */
inline std::uint32_t leafMask(std::uint64_t cells, unsigned leaf) {
  const std::uint64_t c = cells >> (2 * (leaf & 1u) + 4 * (leaf & 2u) + 8 * (leaf & 4u));
  return std::uint32_t((c & 3u) | ((c >> 2) & 0xCu) | ((c >> 12) & 0x30u) | ((c >> 14) & 0xC0u));
}
}  // namespace block_cells

/**
 * Walks rays from one sensor and hands out their cells a 4×4×4 block at a time: for each stretch of a
 * ray inside one block, the block and the cells it passes there (block_cells). The cells are
 * traceSegment's, exactly: the sensor's cell first, the end cell excluded.
 *
 * A cell is one 64-bit word here, relative to an origin near the sensor: bits 0..5 are its block_cells
 * bit, and bits 6..62 its block, 19 bits per axis. A step adds ±1 to one axis's scattered bits (a
 * dilated add: the gaps are filled so the carry crosses them), the cell's bit is the low six bits, and
 * the step entered another block when anything above them changed. The words span kReach cells around
 * the sensor per axis; rays reaching farther walk elsewhere (reaches()).
 *
 * Where the CPU has AVX2, four rays walk side by side in vector lanes. One ray's DDA is a chain of
 * dependent compares and adds, and its branches are hard to predict; four independent chains fill the
 * pipeline instead. With AVX-512VL's 32 registers, two groups of four walk at once. The stretches of
 * different rays then come interleaved. Elsewhere the rays walk one at a time.
 */
class BlockRayWalker {
 public:
  static constexpr std::size_t kBatch = 256;
  /** The origin is aligned to cubes of 2^kAlign cells, so block keys keep their alignment up to there. */
  static constexpr unsigned kAlign = 16;
  /** Cells per axis from the sensor's cell to a ray's end cell, at most: the words leave room for the
   * origin's alignment and the few steps a walk may overshoot. */
  static constexpr std::int64_t kReach = (std::int64_t(1) << 20) - (std::int64_t(1) << kAlign) - 8;
  enum class Lanes { Best, Avx2, Scalar };

  /**
   * `ends` holds `count` xyz triples; every ray's ends must have valid keys that the sensor reaches(), as
   * insertRays checks. A `lanes` choice the CPU cannot run falls back to the next simpler one.
   */
  BlockRayWalker(const CellGrid& grid, const float sensor[3], const float* ends, std::size_t count,
                 Lanes lanes = Lanes::Best);
  /**
   * As above, and ray i's walk begins where it is at distance cuts[i] (RayBundles): the cells before are
   * not handed out, the stretches after are the plain walk's. The lanes take the cuts; the scalar walk
   * walks every ray from the sensor.
   */
  BlockRayWalker(const CellGrid& grid, const float sensor[3], const float* ends, const double* cuts,
                 std::size_t count, Lanes lanes = Lanes::Best);

  /** Whether a ray between these cells stays within kReach of `from` on every axis. */
  static bool reaches(const Key& from, const Key& to);

  /** Walks on until a batch of stretches is ready or the rays are done. Returns the batch size, 0 at the end.
   */
  std::size_t next();

  /** Stretch i's block as a key: one word per block, the same for every ray of this walker. */
  std::uint64_t blockKey(std::size_t i) const { return out_[0][i] >> 6; }
  std::uint64_t cells(std::size_t i) const { return out_[1][i]; }

  /** The block of a key, in tree coordinates / 4. */
  void block(std::uint64_t key, std::uint32_t (&b)[3]) const {
    for (int a = 0; a < 3; ++a) b[a] = block_base_[a] + std::uint32_t(key >> (19 * a) & 0x7FFFFu);
  }

  /**
   * The key bits that tell apart aligned cubes of 2^level cells (2 <= level): keys of one cube agree on
   * them. Cubes beyond kAlign count as that size.
   */
  static std::uint64_t cubeMask(unsigned level) {
    const std::uint64_t low = (std::uint64_t(1) << ((level < kAlign ? level : kAlign) - 2)) - 1;
    return ~(low | low << 19 | low << 38);
  }

  /** Cells of the rays walked to their end: traceSegment's counts, summed. */
  std::uint64_t cellCount() const { return cells_; }
  /** Of those, the cells before the rays' cuts, passed without a step. */
  std::uint64_t skippedCount() const { return skipped_; }

 private:
  static constexpr int kLanes = 8;
  // Up to two stretches per lane and step can come out after the batch fills.
  static constexpr std::size_t kCapacity = kBatch + 2 * kLanes;
  enum class Path { Avx512, Avx2, Scalar };

  /** The word of a cell. */
  std::uint64_t word(const TreeCoord& c) const;
  /** Loads the next ray that passes at least one cell into `lane`; false when none is left. */
  bool startRay(int lane);
  /** Sets up the next kReady rays that pass a cell, each moved to its cut. */
  void prepare();
  static constexpr int kReady = 8;
  /**
   * Moves each ray to its cut: the walk takes each axis's crossings in order of distance, so at the cut it
   * has taken exactly those before it, each axis's summed as the walk sums them.
   */
  void forward(double (&tmax)[3][kReady], const double (&tdelta)[3][kReady], const double (&cut)[kReady],
               std::int64_t (&skip)[3][kReady]) const;
  static void forwardAvx2(double (&tmax)[3][kReady], const double (&tdelta)[3][kReady],
                          const double (&cut)[kReady], std::int64_t (&skip)[3][kReady]);
  /**
   * Ends a lane's step that the vector test flagged, near or past the end cell or beyond the length:
   * `beyond` and `crossed` (into another block) as the lanes found them.
   */
  void finishStep(int lane, bool beyond, bool crossed, std::size_t& n);
  void emit(std::size_t& n, std::uint64_t cell, std::uint64_t cells);
  std::size_t nextScalar();
  std::size_t nextAvx2();
  std::size_t nextAvx512();
  template <int Groups>
  std::size_t walkGroups();

  const CellGrid& grid_;
  const float* sensor_;
  const float* ends_;
  const double* cuts_;
  std::size_t count_, next_ray_ = 0;
  Key from_;
  Path path_;
  std::uint64_t cells_ = 0, skipped_ = 0;
  std::uint32_t origin_[3] = {0, 0, 0};      // tree coordinates of the words' zero, less the bias
  std::uint32_t block_base_[3] = {0, 0, 0};  // origin_ / 4
  std::uint64_t start_ = 0;                  // the sensor cell's word

  // Lane state; a lane whose ray is done and has no successor is not live.
  alignas(32) std::int64_t cell_[kLanes] = {};    // the current cell's word
  alignas(32) std::int64_t prev_[kLanes] = {};    // the word before the last step
  alignas(32) std::int64_t end_[kLanes] = {};     // the end cell's word
  alignas(32) std::int64_t inc_[3][kLanes] = {};  // the word's addend for a step along each axis
  alignas(32) double tmax_[3][kLanes] = {};
  alignas(32) double tdelta_[3][kLanes] = {};
  alignas(32) double length_[kLanes] = {};
  alignas(32) std::int64_t left_[kLanes] = {};   // steps to the end cell; see traceSegment
  alignas(32) std::int64_t span_[kLanes] = {};   // all of them
  alignas(32) std::uint64_t mask_[kLanes] = {};  // the current stretch's cells
  alignas(32) std::uint64_t bit_[kLanes] = {};   // the current cell's
  alignas(32) std::int64_t live_[kLanes] = {};   // -1 or 0

  std::vector<std::uint64_t> out_[2];  // a cell of each stretch, as a word, and its cells

  /** A ray set up for a lane. */
  struct Ready {
    std::int64_t cell, end, left, span;
    std::int64_t inc[3];
    double tmax[3], tdelta[3], length;
  };
  Ready ready_[kReady];
  int ready_next_ = 0, ready_count_ = 0;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
