#include "mapping/scan_cells.h"

namespace pcl {
namespace fot {
namespace detail {
namespace {

std::size_t slotOf(const std::uint32_t (&b)[3], unsigned bits) {
  const std::uint64_t h = (std::uint64_t(b[0]) * 0x9E3779B97F4A7C15ull) ^
                          (std::uint64_t(b[1]) * 0xC2B2AE3D27D4EB4Full) ^
                          (std::uint64_t(b[2]) * 0x165667B19E3779F9ull);
  return std::size_t((h ^ (h >> 31)) >> (64 - bits));
}

}  // namespace

void ScanCells::reset(std::size_t expected_blocks) {
  bits_ = 10;
  while (bits_ < 30 && (std::size_t(1) << bits_) < 2 * expected_blocks) ++bits_;
  slots_.assign(std::size_t(1) << bits_, 0);
  blocks_.clear();
  blocks_.reserve(expected_blocks);
}

ScanCells::Block& ScanCells::find(const std::uint32_t (&b)[3]) {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t s = slotOf(b, bits_);; s = (s + 1) & mask) {
    const std::uint32_t i = slots_[s];
    if (i == 0) {
      if (2 * (blocks_.size() + 1) > slots_.size()) {  // keep the table at most half full
        grow();
        return find(b);
      }
      slots_[s] = std::uint32_t(blocks_.size() + 1);
      blocks_.push_back(Block{{b[0], b[1], b[2]}});
      return blocks_.back();
    }
    Block& block = blocks_[i - 1];
    if (block.at[0] == b[0] && block.at[1] == b[1] && block.at[2] == b[2]) return block;
  }
}

void ScanCells::join(const ScanCells& other) {
  for (const Block& o : other.blocks_) {
    Block& b = find(o.at);
    b.passed |= o.passed;
    b.hit |= o.hit;
  }
}

void ScanCells::grow() {
  ++bits_;
  slots_.assign(std::size_t(1) << bits_, 0);
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    std::size_t s = slotOf(blocks_[i].at, bits_);
    while (slots_[s] != 0) s = (s + 1) & mask;
    slots_[s] = std::uint32_t(i + 1);
  }
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
