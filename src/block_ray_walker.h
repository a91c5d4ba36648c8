#pragma once
// Private to the library: the scan insertion's ray walk, many rays at a time.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <pcl_fot/key.h>
#include <pcl_fot/ray_caster.h>

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
/** A leaf's cells in `cells` as a leaf mask: bit o for the cell in octant o. */
inline std::uint32_t leafMask(std::uint64_t cells, unsigned leaf) {
  const std::uint64_t c = cells >> (2 * (leaf & 1u) + 4 * (leaf & 2u) + 8 * (leaf & 4u));
  return std::uint32_t((c & 3u) | ((c >> 2) & 0xCu) | ((c >> 12) & 0x30u) | ((c >> 14) & 0xC0u));
}
}  // namespace block_cells

/**
 * Walks rays from one sensor and hands out their cells a 4×4×4 block at a time: for each stretch of a
 * ray inside one block, the block (tree coordinates / 4) and the cells it passes there (block_cells).
 * The cells are traceSegment's, exactly: the sensor's cell first, the end cell excluded.
 *
 * Where the CPU has AVX2, four rays walk side by side in vector lanes. One ray's DDA is a chain of
 * dependent compares and adds, and its branches are hard to predict; four independent chains fill the
 * pipeline instead. With AVX-512VL's 32 registers, two groups of four walk at once. The stretches of
 * different rays then come interleaved. Elsewhere the rays walk one at a time.
 */
class BlockRayWalker {
 public:
  static constexpr std::size_t kBatch = 256;
  enum class Lanes { Best, Avx2, Scalar };

  /**
   * `ends` holds `count` xyz triples; every ray's ends must have valid keys, as insertRays checks. A
   * `lanes` choice the CPU cannot run falls back to the next simpler one.
   */
  BlockRayWalker(const VoxelGrid& grid, const float sensor[3], const float* ends, std::size_t count,
                 Lanes lanes = Lanes::Best);

  /** Walks on until a batch of stretches is ready or the rays are done. Returns the batch size, 0 at the end.
   */
  std::size_t next();

  // A stretch is stored as one of its cells.
  std::uint32_t blockX(std::size_t i) const { return std::uint32_t(out_[0][i] >> 2); }
  std::uint32_t blockY(std::size_t i) const { return std::uint32_t(out_[1][i] >> 2); }
  std::uint32_t blockZ(std::size_t i) const { return std::uint32_t(out_[2][i] >> 2); }
  std::uint64_t cells(std::size_t i) const { return out_[3][i]; }

  /** Cells of the rays walked to their end: traceSegment's counts, summed. */
  std::uint64_t cellCount() const { return cells_; }

 private:
  static constexpr int kLanes = 8;
  // Up to two stretches per lane and step can come out after the batch fills.
  static constexpr std::size_t kCapacity = kBatch + 2 * kLanes;
  enum class Path { Avx512, Avx2, Scalar };

  /** Loads the next ray that passes at least one cell into `lane`; false when none is left. */
  bool startRay(int lane);
  /**
   * Ends a lane's step that the vector test flagged, near or past the end cell or beyond the length:
   * `beyond` and `crossed` (into another block) as the lanes found them.
   */
  void finishStep(int lane, bool beyond, bool crossed, std::size_t& n);
  void emit(std::size_t& n, std::uint64_t x, std::uint64_t y, std::uint64_t z, std::uint64_t cells);
  std::size_t nextScalar();
  std::size_t nextAvx2();
  std::size_t nextAvx512();
  template <int Groups>
  std::size_t walkGroups();

  const VoxelGrid& grid_;
  const float* sensor_;
  const float* ends_;
  std::size_t count_, next_ray_ = 0;
  Key from_;
  Path path_;
  std::uint64_t cells_ = 0;

  // Lane state, in tree coordinates; a lane whose ray is done and has no successor is not live.
  alignas(32) std::int64_t u_[3][kLanes] = {};     // the current cell
  alignas(32) std::int64_t prev_[3][kLanes] = {};  // the cell before the last step
  alignas(32) std::int64_t step_[3][kLanes] = {};  // -1, 0, 1
  alignas(32) std::int64_t end_[3][kLanes] = {};   // the end cell
  alignas(32) double tmax_[3][kLanes] = {};
  alignas(32) double tdelta_[3][kLanes] = {};
  alignas(32) double length_[kLanes] = {};
  alignas(32) std::int64_t left_[kLanes] = {};   // steps to the end cell; see traceSegment
  alignas(32) std::int64_t span_[kLanes] = {};   // all of them
  alignas(32) std::uint64_t mask_[kLanes] = {};  // the current stretch's cells
  alignas(32) std::uint64_t bit_[kLanes] = {};   // the current cell's
  alignas(32) std::int64_t live_[kLanes] = {};   // -1 or 0

  std::vector<std::uint64_t> out_[4];  // x, y, z of a cell and the cells of each stretch
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
