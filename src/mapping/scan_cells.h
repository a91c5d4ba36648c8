#pragma once
// Private to the library: one scan's cells, each once, for the log-odds rule.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <pcl_fot/mapping/scan_insertion.h>
#include <pcl_fot/tree/key.h>
#include <pcl_fot/tree/tree_coord.h>

namespace pcl {
namespace fot {
namespace detail {

/**
 * The cells one scan updates, as OctoMap's computeUpdate collects them in its two key sets: every cell a
 * ray passes, and every endpoint's cell, each once. They are kept a 4×4×4 block at a time (tree coordinates
 * / 4, cells as block_cells bits), in the order the rays first reach each block (share by share, once
 * joined), so that writing them in that order keeps LineBurstAccess's paths short.
 */
class ScanCells {
 public:
  using Block = ScanBlock;

  explicit ScanCells(std::size_t expected_blocks) { reset(expected_blocks); }

  /** Empties it for a scan of about `expected_blocks` blocks; keeps its buffers. */
  void reset(std::size_t expected_blocks);

  /** The index of a block, added if new: it stays valid while cells are added. */
  std::uint32_t index(const std::uint32_t (&block)[3]) {
    return std::uint32_t(&find(block) - blocks_.data());
  }
  void pass(std::uint32_t index, std::uint64_t cells) { blocks_[index].passed |= cells; }
  void pass(const Key& k) { cell(k, &Block::passed); }
  void hit(const Key& k) { cell(k, &Block::hit); }
  /** Adds another share's cells: its blocks new here come after this one's, in its order. */
  void join(const ScanCells& other);

  const std::vector<Block>& blocks() const { return blocks_; }

 private:
  void cell(const Key& k, std::uint64_t Block::*field) {
    const TreeCoord c(k);
    const std::uint32_t b[3] = {c[0] >> 2, c[1] >> 2, c[2] >> 2};
    find(b).*field |= std::uint64_t(1) << ((c[0] & 3u) + 4 * (c[1] & 3u) + 16 * (c[2] & 3u));
  }
  Block& find(const std::uint32_t (&b)[3]);
  void grow();

  std::vector<Block> blocks_;
  std::vector<std::uint32_t> slots_;  // 1 + index into blocks_, or 0 for an empty slot
  unsigned bits_ = 10;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
