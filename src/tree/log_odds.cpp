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
  auto walk = [&](auto& self, std::size_t at, unsigned level) -> void {
    const NodeWord w = words_[at];
    if (node::isBitmap(w)) {
      if (!node::hasValues(w)) return;
      for (unsigned o = 0; o < 8; ++o) {
        const float v = leafValue(at, o);
        if (!std::isnan(v) && !model_.settled(v)) n += node::cellsIn(1, level - 1);
      }
      return;
    }
    for (unsigned o = 0; o < 8; ++o) self(self, node::childOffset(w, o), level - 1);
  };
  walk(walk, 0, root_level_);
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
    values_.release(w, at);
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
  if (node::hasValues(w)) {
    values_.values(w, at, v);
    return;
  }
  for (unsigned o = 0; o < 8; ++o) v[o] = settledValue(node::state(w, o));
}

void FastOctTree::installValues(std::vector<float> values) {
  values_.releaseRows();
  if (values.empty()) return;
  std::size_t next = 0;
  auto walk = [&](auto& self, std::size_t at, unsigned level) -> void {
    const NodeWord w = words_[at];
    if (node::isBitmap(w)) {
      if (!node::hasValues(w)) return;
      float v[8];
      std::memcpy(v, &values[8 * next++], sizeof v);
      const NodeWord states = w & ~node::kValueFlag;  // no values yet
      if (level == 1) {
        words_[at] = values_.store(at, states, states, v, pool());
      } else {  // cubes of one value (checked), which only the palette holds
        const unsigned known = unsigned(__builtin_ctz(~node::octantMask(w, CellState::Unknown)));
        words_[at] = values_.named(states, v[known]);
        if (words_[at] == 0)
          throw MemoryLimitError("pcl::fot::FastOctTree: the palette of 16382 values is full");
      }
      ++value_leaves_;
      return;
    }
    for (unsigned o = 0; o < 8; ++o) self(self, node::childOffset(w, o), level - 1);
  };
  walk(walk, 0, root_level_);
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
    values_.release(words_[at], at);
  } else {
    float canonical[8];  // one NaN for every unknown cell
    for (unsigned o = 0; o < 8; ++o) canonical[o] = std::isnan(v[o]) ? kUnknownValue : v[o];
    w = values_.store(at, words_[at], w, canonical, pool());
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
  // The cube's cells as this map holds them: one value, or structure to split along.
  const std::uint32_t apart = (c[0] ^ base_[0]) | (c[1] ^ base_[1]) | (c[2] ^ base_[2]);
  float value = kUnknownValue;
  bool is_uniform = true;
  if (!empty() && level <= root_level_ && (apart >> root_level_) == 0) {
    std::size_t at = 0;
    unsigned l = root_level_;
    for (; l > level && !node::isBitmap(words_[at]); --l) at = node::childOffset(words_[at], c.octant(l));
    const NodeWord w = words_[at];
    if (l > level) {
      value = leafValue(at, c.octant(l));  // inside one octant of a bitmap
    } else {
      is_uniform = node::isUniform(w) || node::isValueUniform(w);
      value = leafValue(at, 0);
    }
  } else if (!empty()) {
    is_uniform = (apart >> level) != 0;  // disjoint from the root (unknown), or holding it (split)
  }
  if (is_uniform) {
    if (model_.updateNode(value, update)) setCubeLogOdds(c, level, value);
    return;
  }
  for (unsigned o = 0; o < 8; ++o) updateCube(c.child(o, level - 1), level - 1, update);
}

void FastOctTree::setCubeLogOdds(const TreeCoord& c, unsigned level, float log_odds) {
  const CellState s = std::isnan(log_odds)
                          ? CellState::Unknown
                          : (model_.occupied(log_odds) ? CellState::Occupied : CellState::Free);
  if (s == CellState::Unknown || model_.settled(log_odds)) {
    setCube(c, level, s);
    return;
  }
  if (level == 0) {
    Accessor(*this, false).setLogOdds(c.key(), log_odds);
    return;
  }
  const NodeWord cube = values_.named(node::uniform(s), log_odds);
  if (cube != 0) {
    writeCube(c, level, cube);
    return;
  }
  for (unsigned o = 0; o < 8; ++o)
    setCubeLogOdds(c.child(o, level - 1), level - 1, log_odds);  // palette full
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
      updateCube(TreeCoord(r.min_key), r.level, log_odds);  // a cube of one value: whole cubes at once
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
