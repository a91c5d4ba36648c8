#include <pcl_fot/tree/leaf_values.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

namespace pcl {
namespace fot {

void LeafValues::values(NodeWord w, std::size_t at, float (&v)[8]) const {
  const std::uint32_t p = node::palette(w);
  if (p == 0) {
    std::memcpy(v, float_rows_.at(row_of_[at]), sizeof v);
  } else if (p == node::kByteRow) {
    const std::uint8_t* index = byte_rows_.at(row_of_[at]);
    for (unsigned o = 0; o < 8; ++o) v[o] = palette_[index[o]];  // entry 0, unknown, is NaN
  } else {
    const std::uint32_t known = ~node::octantMask(w, CellState::Unknown);
    for (unsigned o = 0; o < 8; ++o)
      v[o] = (known >> o) & 1u ? palette_[p] : std::numeric_limits<float>::quiet_NaN();
  }
}

std::uint32_t LeafValues::paletteIndex(float value) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  // A map's leaves share a few values: a small table answers before the hash map.
  PaletteHit& hit = palette_hits_[(bits * 0x9E3779B1u) >> (32 - kPaletteHitBits)];
  if (hit.index != 0 && hit.bits == bits) return hit.index;
  const auto found = palette_of_.find(bits);
  std::uint32_t index = 0;
  if (found != palette_of_.end()) {
    index = found->second;
  } else if (palette_.size() < node::kByteRow) {  // room: 1 .. kByteRow - 1
    if (palette_.empty()) palette_.push_back(std::numeric_limits<float>::quiet_NaN());  // index 0: none
    palette_.push_back(value);
    index = palette_of_[bits] = std::uint32_t(palette_.size() - 1);
  }
  hit = PaletteHit{bits, index};
  return index;
}

NodeWord LeafValues::store(std::size_t at, NodeWord old, NodeWord states, const float (&v)[8],
                           const Pool& pool) {
  // One value in every known cell, bit for bit (-0.0 is not 0.0 here): the word names it.
  const float* one = nullptr;
  bool uniform = true;
  for (const float& x : v)
    if (!std::isnan(x)) {
      uniform = uniform && (!one || std::memcmp(&x, one, sizeof x) == 0);
      one = &x;
    }
  const std::uint32_t p = uniform && one ? paletteIndex(*one) : 0;
  if (p != 0) {
    release(old, at);
    return states | node::kValueFlag | (p << node::kPaletteShift);
  }
  // Values among the palette's first 255: a byte per cell, its palette index (0 where unknown).
  std::uint8_t index[8];
  bool bytes = true;
  for (unsigned o = 0; o < 8 && bytes; ++o) {
    const std::uint32_t q = std::isnan(v[o]) ? 0 : paletteIndex(v[o]);
    bytes = std::isnan(v[o]) || (q != 0 && q <= 0xFF);
    index[o] = std::uint8_t(q);
  }
  const std::uint32_t kind = bytes ? node::kByteRow : 0;
  if (!node::hasValueRow(old) || node::palette(old) != kind) {
    reserveRow(pool);
    const std::uint32_t row = bytes ? byte_rows_.allocate() : float_rows_.allocate();
    release(old, at);  // the old row: the new one keeps the index alive
    row_of_[at] = row;
  }
  if (bytes)
    std::memcpy(byte_rows_.at(row_of_[at]), index, sizeof index);
  else
    std::memcpy(float_rows_.at(row_of_[at]), v, sizeof v);
  return states | node::kValueFlag | (kind << node::kPaletteShift);
}

void LeafValues::reserveRow(const Pool& pool, std::size_t extra_words) {
  const std::size_t bytes = 2 * (pool.words + extra_words) * sizeof(NodeWord) + rowBytes() +
                            float_rows_.growth() + byte_rows_.growth();
  if (bytes > pool.max_bytes)
    throw MemoryLimitError("pcl::fot::FastOctTree: the pool and its values would need " +
                           std::to_string(bytes) + " bytes, beyond the cap of " +
                           std::to_string(pool.max_bytes) + " bytes");
  if (row_of_.empty()) {
    row_of_.reserve(pool.capacity);
    row_of_.resize(pool.words);
  }
}

void LeafValues::release(NodeWord w, std::size_t at) {
  if (!node::hasValueRow(w)) return;
  if (node::palette(w) == 0)
    float_rows_.release(row_of_[at]);
  else
    byte_rows_.release(row_of_[at]);
  // No row left, as when a scan repeated until it clamps settles every cell: no index either.
  if (rowCount() == 0) std::vector<std::uint32_t>().swap(row_of_);
}

void LeafValues::releaseRows() {
  std::vector<std::uint32_t>().swap(row_of_);
  float_rows_.clear();
  byte_rows_.clear();
}

void LeafValues::clear() {
  releaseRows();
  palette_.clear();
  palette_of_.clear();
  palette_hits_ = {};
}

void LeafValues::shrinkToFit(bool palette_unused) {
  if (palette_unused) {
    std::vector<float>().swap(palette_);
    std::unordered_map<std::uint32_t, std::uint32_t>().swap(palette_of_);
    palette_hits_ = {};
  }
  row_of_.shrink_to_fit();
  float_rows_.shrinkToFit();
  byte_rows_.shrinkToFit();
}

}  // namespace fot
}  // namespace pcl
