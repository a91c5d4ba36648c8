// The tree's log-odds: the values of flagged leaves, their updates, and merging maps.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace {

void checkFinite(const char* where, float v) {
  if (!std::isfinite(v)) throw std::invalid_argument(std::string(where) + ": the log-odds is not finite");
}

}  // namespace

void FastOctTree::setSensorModel(const SensorModel& model) {
  const bool same_cells = model.clampMinLogOdds() == model_.clampMinLogOdds() &&
                          model.clampMaxLogOdds() == model_.clampMaxLogOdds() &&
                          model.occupancyLogOdds() == model_.occupancyLogOdds();
  if (!same_cells && !empty())
    throw std::logic_error(
        "pcl::fot::FastOctTree::setSensorModel: the clamps and the threshold define the settled cells; "
        "change them only on an empty map");
  model_ = model;
}

float FastOctTree::getLogOdds(const Key& key) const {
  return ConstAccessor(*this, false).getLogOdds(key);
}

double FastOctTree::getProbability(const Key& key) const {
  return SensorModel::probability(getLogOdds(key));
}

void FastOctTree::updateLogOdds(const Key& key, float update) {
  checkFinite("pcl::fot::FastOctTree::updateLogOdds", update);
  Accessor(*this, false).updateCell(key, update);
}

void FastOctTree::setLogOdds(const Key& key, float log_odds) {
  checkFinite("pcl::fot::FastOctTree::setLogOdds", log_odds);
  Accessor(*this, false).setLogOdds(key, log_odds);
}

std::uint64_t FastOctTree::getUnsettledCount() const {
  std::uint64_t n = 0;
  auto walk = [&](auto& self, std::size_t at) -> void {
    const NodeWord w = words_[at];
    if (node::isBitmap(w)) {
      if (!node::hasValues(w)) return;
      for (unsigned o = 0; o < 8; ++o) {
        const float v = leafValue(at, o);
        n += !std::isnan(v) && !model_.settled(v);
      }
      return;
    }
    for (unsigned o = 0; o < 8; ++o) self(self, node::childOffset(w, o));
  };
  walk(walk, 0);
  return n;
}

void FastOctTree::toMaxLikelihood() {
  if (value_leaves_ == 0) return;
  settleSubtree(0);
  value_leaves_ = 0;
  ++version_;
}

NodeWord FastOctTree::settleSubtree(std::size_t at) {
  NodeWord w = words_[at];
  if (node::isBitmap(w)) {
    releaseValues(at);
    return words_[at] = w & ~(node::kValueFlag | node::kPaletteMask);
  }
  NodeWord folded = node::kBitmapTag;
  bool uniform = true;
  for (unsigned o = 0; o < 8; ++o) {
    const NodeWord child = settleSubtree(node::childOffset(w, o));
    uniform = uniform && node::isUniform(child);
    folded = node::withState(folded, o, node::uniformState(child));
  }
  if (!uniform) return w;
  freeBlock(node::block(w));
  return words_[at] = folded;
}

void FastOctTree::leafValues(std::size_t at, float (&v)[8]) const {
  const NodeWord w = words_[at];
  const std::uint32_t p = node::palette(w);
  if (!node::hasValues(w)) {
    for (unsigned o = 0; o < 8; ++o) v[o] = settledValue(node::state(w, o));
  } else if (p == 0) {
    std::memcpy(v, float_blocks_.at(value_of_[at]), sizeof v);
  } else if (p == node::kByteBlock) {
    const std::uint8_t* index = byte_blocks_.at(value_of_[at]);
    for (unsigned o = 0; o < 8; ++o) v[o] = palette_[index[o]];  // entry 0, unknown, is NaN
  } else {
    const std::uint32_t known = ~node::octantMask(w, CellState::Unknown);
    for (unsigned o = 0; o < 8; ++o) v[o] = (known >> o) & 1u ? palette_[p] : kUnknownValue;
  }
}

std::uint32_t FastOctTree::paletteIndex(float value) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  // A map's leaves share a few values: a small table answers before the hash map.
  PaletteHit& hit = palette_hits_[(bits * 0x9E3779B1u) >> (32 - kPaletteHitBits)];
  if (hit.index != 0 && hit.bits == bits) return hit.index;
  const auto found = palette_of_.find(bits);
  std::uint32_t index = 0;
  if (found != palette_of_.end()) {
    index = found->second;
  } else if (palette_.size() < node::kByteBlock) {            // room: 1 .. kByteBlock - 1
    if (palette_.empty()) palette_.push_back(kUnknownValue);  // index 0: no palette
    palette_.push_back(value);
    index = palette_of_[bits] = std::uint32_t(palette_.size() - 1);
  }
  hit = PaletteHit{bits, index};
  return index;
}

NodeWord FastOctTree::storeValues(std::size_t at, NodeWord states, const float (&v)[8]) {
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
    releaseValues(at);
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
  const std::uint32_t kind = bytes ? node::kByteBlock : 0;
  const NodeWord old = words_[at];
  if (!node::hasValueBlock(old) || node::palette(old) != kind) {
    reserveValueBlock();
    const std::uint32_t block = bytes ? byte_blocks_.allocate() : float_blocks_.allocate();
    releaseValues(at);  // the old block: the new one keeps the index alive
    value_of_[at] = block;
  }
  if (bytes)
    std::memcpy(byte_blocks_.at(value_of_[at]), index, sizeof index);
  else
    std::memcpy(float_blocks_.at(value_of_[at]), v, sizeof v);
  return states | node::kValueFlag | (kind << node::kPaletteShift);
}

void FastOctTree::installValues(std::vector<float> values) {
  releaseAllValues();
  if (values.empty()) return;
  std::size_t next = 0;
  auto walk = [&](auto& self, std::size_t at) -> void {
    const NodeWord w = words_[at];
    if (node::isBitmap(w)) {
      if (!node::hasValues(w)) return;
      float v[8];
      std::memcpy(v, &values[8 * next++], sizeof v);
      words_[at] = w & ~node::kValueFlag;  // no values yet
      words_[at] = storeValues(at, words_[at], v);
      ++value_leaves_;
      return;
    }
    for (unsigned o = 0; o < 8; ++o) self(self, node::childOffset(w, o));
  };
  walk(walk, 0);
}

void FastOctTree::reserveValueBlock(std::size_t extra_words) {
  const std::size_t bytes = 2 * (words_.size() + extra_words) * sizeof(NodeWord) + float_blocks_.bytes() +
                            float_blocks_.growth() + byte_blocks_.bytes() + byte_blocks_.growth();
  if (bytes > max_bytes_)
    throw MemoryLimitError("pcl::fot::FastOctTree: the pool and its values would need " +
                           std::to_string(bytes) + " bytes, beyond the cap of " + std::to_string(max_bytes_) +
                           " bytes");
  if (value_of_.empty()) {
    value_of_.reserve(words_.capacity());
    value_of_.resize(words_.size());
  }
}

void FastOctTree::releaseValues(std::size_t at) {
  const NodeWord w = words_[at];
  if (!node::hasValueBlock(w)) return;
  if (node::palette(w) == 0)
    float_blocks_.release(value_of_[at]);
  else
    byte_blocks_.release(value_of_[at]);
  // No block left, as when a scan repeated until it clamps settles every cell: no index either.
  if (getValueBlockCount() == 0) std::vector<std::uint32_t>().swap(value_of_);
}

void FastOctTree::releaseAllValues() {
  std::vector<std::uint32_t>().swap(value_of_);
  float_blocks_.clear();
  byte_blocks_.clear();
}

unsigned FastOctTree::commitLeaf(const std::size_t* path, const float (&v)[8]) {
  const std::size_t at = path[1];
  NodeWord w = node::kBitmapTag;
  bool settled = true;
  for (unsigned o = 0; o < 8; ++o) {
    if (std::isnan(v[o])) continue;
    w = node::withState(w, o, model_.occupied(v[o]) ? CellState::Occupied : CellState::Free);
    settled = settled && model_.settled(v[o]);
  }
  if (settled) {
    releaseValues(at);
  } else {
    float canonical[8];  // one NaN for every unknown cell
    for (unsigned o = 0; o < 8; ++o) canonical[o] = std::isnan(v[o]) ? kUnknownValue : v[o];
    w = storeValues(at, w, canonical);
  }
  return writeLeaf(path, w);
}

unsigned FastOctTree::updateLeaf(const std::size_t* path, std::uint32_t mask, const float* update) {
  float v[8];
  leafValues(path[1], v);
  bool changed = false;
  for (std::uint32_t m = mask; m != 0; m &= m - 1) {
    const unsigned o = unsigned(__builtin_ctz(m));
    changed |= model_.updateNode(v[o], update[o]);
  }
  return changed ? commitLeaf(path, v) : 1;
}

unsigned FastOctTree::setLeafStates(const std::size_t* path, std::uint32_t mask, CellState state) {
  float v[8];
  leafValues(path[1], v);
  for (unsigned o = 0; o < 8; ++o)
    if ((mask >> o) & 1u) v[o] = settledValue(state);
  return commitLeaf(path, v);
}

unsigned FastOctTree::setLeafValue(const std::size_t* path, unsigned o, float value) {
  float v[8];
  leafValues(path[1], v);
  v[o] = value;
  return commitLeaf(path, v);
}

void FastOctTree::updateCube(const TreeCoord& c, unsigned level, float update) {
  if (level == 0) {
    Accessor(*this, false).updateCell(c.key(), update);
    return;
  }
  // The cube's cells as this map holds them: one uniform state, or structure to split along.
  NodeView n = root();
  const std::uint32_t apart = (c[0] ^ n.corner[0]) | (c[1] ^ n.corner[1]) | (c[2] ^ n.corner[2]);
  CellState uniform = CellState::Unknown;
  bool is_uniform = true;
  if (empty()) {
    is_uniform = true;
  } else if (level <= root_level_ && (apart >> root_level_) == 0) {
    while (n.level > level && !n.isUniform()) n = n.child(words_.data(), c.octant(n.level));
    is_uniform = n.isUniform();
    uniform = n.uniformState();
  } else {
    is_uniform = (apart >> level) != 0;  // disjoint from the root (unknown), or holding it (split)
  }
  if (is_uniform) {
    float after = settledValue(uniform);
    model_.updateNode(after, update);
    if (model_.settled(after)) {
      setCube(c, level, model_.occupied(after) ? CellState::Occupied : CellState::Free);
      return;
    }
  }
  for (unsigned o = 0; o < 8; ++o) updateCube(c.child(o, level - 1), level - 1, update);
}

void FastOctTree::merge(const FastOctTree& other) {
  if (other.grid_ != grid_)
    throw std::invalid_argument(
        "pcl::fot::FastOctTree::merge: the maps' grids differ (resolution or origin); merge maps of one "
        "grid");
  if (&other == this) {
    const FastOctTree copy(other);
    merge(copy);
    return;
  }
  // The cells of one 2×2×2 leaf come one after another (Morton order): they are written together.
  Accessor accessor(*this, true);
  Key leaf{};
  std::uint32_t mask = 0;
  float update[8];
  const auto flush = [&] {
    if (mask != 0) accessor.updateLeafCells(leaf, mask, update);
    mask = 0;
  };
  other.forEachLogOdds([&](const Region& r, float log_odds) {
    if (r.level > 0) {
      flush();
      updateCube(TreeCoord(r.min_key), r.level, log_odds);  // a settled cube: whole cubes at once
      return;
    }
    const TreeCoord c(r.min_key), l(leaf);
    if (mask != 0 && ((c[0] ^ l[0]) | (c[1] ^ l[1]) | (c[2] ^ l[2])) >> 1 != 0) flush();
    leaf = r.min_key;
    const unsigned o = c.octant(1);
    mask |= 1u << o;
    update[o] = log_odds;
  });
  flush();
}

}  // namespace fot
}  // namespace pcl
