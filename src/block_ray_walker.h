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
 * Walks rays from one sensor and hands out their cells a 4×4×4 block at a time: for each stretch of a
 * ray inside one block, the block (tree coordinates / 4) and the cells it passes there (bit 8 × leaf
 * octant + cell octant). The cells are traceSegment's, exactly: the sensor's cell first, the end cell
 * excluded.
 *
 * Where the CPU has AVX2, four rays walk side by side in vector lanes. One ray's DDA is a chain of
 * dependent compares and adds, and its branches are hard to predict; four independent chains fill the
 * pipeline instead. The stretches of different rays then come interleaved. Elsewhere the rays walk one at
 * a time.
 */
class BlockRayWalker {
 public:
  static constexpr std::size_t kBatch = 256;
  enum class Lanes { Best, Scalar };

  /** `ends` holds `count` xyz triples; every ray's ends must have valid keys, as insertRays checks. */
  BlockRayWalker(const VoxelGrid& grid, const float sensor[3], const float* ends, std::size_t count,
                 Lanes lanes = Lanes::Best);

  /** Walks on until a batch of stretches is ready or the rays are done. Returns the batch size, 0 at the end.
   */
  std::size_t next();

  std::uint32_t blockX(std::size_t i) const { return std::uint32_t(out_[0][i]); }
  std::uint32_t blockY(std::size_t i) const { return std::uint32_t(out_[1][i]); }
  std::uint32_t blockZ(std::size_t i) const { return std::uint32_t(out_[2][i]); }
  std::uint64_t cells(std::size_t i) const { return out_[3][i]; }

  /** Cells the rays walked so far: traceSegment's counts, summed. */
  std::uint64_t cellCount() const;

 private:
  static constexpr int kLanes = 4;
  // Up to two stretches per lane and step can come out after the batch fills.
  static constexpr std::size_t kCapacity = kBatch + 2 * kLanes;

  /** Loads the next ray that passes at least one cell into `lane`; false when none is left. */
  bool startRay(int lane);
  void emit(std::size_t& n, std::uint64_t bx, std::uint64_t by, std::uint64_t bz, std::uint64_t cells);
  std::size_t nextScalar();
  std::size_t nextAvx2();

  const VoxelGrid& grid_;
  const float* sensor_;
  const float* ends_;
  std::size_t count_, next_ray_ = 0;
  Key from_;
  bool avx2_;
  std::uint64_t scalar_cells_ = 0;

  // Lane state, in tree coordinates; a lane whose ray is done and has no successor is not live.
  alignas(32) std::int64_t u_[3][kLanes] = {};     // the current cell
  alignas(32) std::int64_t step_[3][kLanes] = {};  // -1, 0, 1
  alignas(32) std::int64_t end_[3][kLanes] = {};   // the end cell
  alignas(32) double tmax_[3][kLanes] = {};
  alignas(32) double tdelta_[3][kLanes] = {};
  alignas(32) double length_[kLanes] = {};
  alignas(32) std::int64_t left_[kLanes] = {};      // steps to the end cell; see traceSegment
  alignas(32) std::int64_t block_[3][kLanes] = {};  // the current stretch's block
  alignas(32) std::uint64_t mask_[kLanes] = {};     // and its cells
  alignas(32) std::int64_t live_[kLanes] = {};      // -1 or 0
  alignas(32) std::int64_t walked_[kLanes] = {};    // cells, counted down per lane
  std::uint64_t started_cells_ = 0;

  std::vector<std::uint64_t> out_[4];  // block x, y, z and cells of each stretch
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
