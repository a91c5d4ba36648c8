#include <pcl_fot/tree/fast_oct_tree.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include <pcl_fot/tree/accessor.h>

namespace pcl {
namespace fot {

void throwKeyOutOfRange(const char* where, const Key& key) {
  throw std::out_of_range(std::string(where) + ": key " + toString(key) +
                          " is outside the supported range [" + std::to_string(kMinKey) + ", " +
                          std::to_string(kMaxKey) + "] per axis");
}

FastOctTree::FastOctTree(double resolution, double origin_x, double origin_y, double origin_z)
    : FastOctTree(CellGrid(resolution, origin_x, origin_y, origin_z)) {}

FastOctTree::FastOctTree(const CellGrid& grid) : grid_(grid), words_(8, 0) {
  words_[0] = node::uniform(CellState::Unknown);
}

CellState FastOctTree::getCell(const Key& key) const {
  return ConstAccessor(*this, false).getCell(key);
}

void FastOctTree::setCell(const Key& key, CellState state) {
  Accessor(*this, false).setCell(key, state);
}

CellState FastOctTree::getCellAtPoint(double x, double y, double z) const {
  Key key;
  return grid_.finitePointToKey(x, y, z, key, "pcl::fot::FastOctTree::getCellAtPoint") ? getCell(key)
                                                                                       : CellState::Unknown;
}

void FastOctTree::setCellAtPoint(double x, double y, double z, CellState state) {
  Key key;
  if (!grid_.finitePointToKey(x, y, z, key, "pcl::fot::FastOctTree::setCellAtPoint"))
    throw std::out_of_range("pcl::fot::FastOctTree::setCellAtPoint: the point lies beyond the key range of " +
                            std::to_string(kMaxKey) + " cells from the map origin");
  setCell(key, state);
}

InsertStats FastOctTree::insertKeys(const Key* keys, std::size_t count, CellState state, bool line_burst) {
  Accessor accessor(*this, line_burst);
  InsertStats stats;
  for (std::size_t i = 0; i < count; ++i) {
    if (!isValidKey(keys[i])) {
      ++stats.out_of_range;
      continue;
    }
    accessor.setCell(keys[i], state);
    ++stats.inserted;
  }
  return stats;
}

InsertStats FastOctTree::insertPoints(const float* xyz, std::size_t count, std::size_t stride_bytes,
                                      CellState state, bool line_burst) {
  Accessor accessor(*this, line_burst);
  InsertStats stats;
  const char* bytes = reinterpret_cast<const char*>(xyz);
  for (std::size_t i = 0; i < count; ++i) {
    const float* p = reinterpret_cast<const float*>(bytes + i * stride_bytes);
    Key key;
    if (grid_.pointToKey(p[0], p[1], p[2], key)) {
      accessor.setValidCell(key, state);
      ++stats.inserted;
    } else if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) {
      ++stats.out_of_range;
    } else {
      ++stats.non_finite;
    }
  }
  return stats;
}

namespace {

constexpr NodeWord kValueBits = node::kValueFlag | node::kPaletteMask;  // a flagged word's value

/** Checks a box for setBox and setBoxLogOdds. */
void checkBox(const char* where, const Key& lo, const Key& hi) {
  if (!isValidKey(lo)) throwKeyOutOfRange(where, lo);
  if (!isValidKey(hi)) throwKeyOutOfRange(where, hi);
  if (lo.x > hi.x || lo.y > hi.y || lo.z > hi.z)
    throw std::invalid_argument(std::string(where) + ": the box " + toString(lo) + " to " + toString(hi) +
                                " is empty");
  const std::uint64_t sx = std::uint64_t(hi.x - lo.x) + 1, sy = std::uint64_t(hi.y - lo.y) + 1,
                      sz = std::uint64_t(hi.z - lo.z) + 1;
  if ((unsigned __int128)(sx * sy) * sz >= (unsigned __int128)1 << 60)
    throw std::invalid_argument(std::string(where) + ": the box holds 2^60 cells or more");
}

/** Splits the smallest aligned cube holding the box [l, h] down to the cubes inside it: write(corner, level).
 */
template <typename Write>
void forEachCubeInBox(const TreeCoord& l, const TreeCoord& h, Write&& write) {
  auto split = [&](auto& self, const TreeCoord& c, unsigned level) -> void {
    const std::uint64_t last = (std::uint64_t(1) << level) - 1;
    bool inside = true;
    for (unsigned a = 0; a < 3; ++a) {
      if (c[a] > h[a] || c[a] + last < l[a]) return;
      inside = inside && c[a] >= l[a] && c[a] + last <= h[a];
    }
    if (inside) {
      write(c, level);
      return;
    }
    for (unsigned o = 0; o < 8; ++o) self(self, c.child(o, level - 1), level - 1);
  };
  const unsigned top = commonLevel(l, h);
  split(split, l.corner(top), top);
}

}  // namespace

void FastOctTree::setBox(const Key& lo, const Key& hi, CellState state) {
  checkBox("pcl::fot::FastOctTree::setBox", lo, hi);
  forEachCubeInBox(TreeCoord(lo), TreeCoord(hi),
                   [&](const TreeCoord& c, unsigned level) { setCube(c, level, state); });
}

void FastOctTree::setBoxLogOdds(const Key& lo, const Key& hi, float log_odds) {
  checkBox("pcl::fot::FastOctTree::setBoxLogOdds", lo, hi);
  if (std::isinf(log_odds))
    throw std::invalid_argument("pcl::fot::FastOctTree::setBoxLogOdds: the log-odds is infinite");
  forEachCubeInBox(TreeCoord(lo), TreeCoord(hi),
                   [&](const TreeCoord& c, unsigned level) { setCubeLogOdds(c, level, log_odds); });
}

void FastOctTree::setCube(const TreeCoord& c, unsigned level, CellState state) {
  if (level == 0) {
    Accessor(*this, false).setValidCell(c.key(), state);
    return;
  }
  writeCube(c, level, node::uniform(state));
}

void FastOctTree::writeCube(const TreeCoord& c, unsigned level, NodeWord cube) {
  const CellState state = node::state(cube, 0);
  const std::uint32_t x = c[0], y = c[1], z = c[2];
  const std::uint32_t apart = (x ^ base_[0]) | (y ^ base_[1]) | (z ^ base_[2]);
  const bool cube_in_root = level <= root_level_ && (apart >> root_level_) == 0;
  const bool root_in_cube = root_level_ <= level && (apart >> level) == 0;
  if (!cube_in_root) {
    if (state == CellState::Unknown) {  // nothing is known outside the root
      if (root_in_cube) {
        ++version_;
        releaseSubtree(0, root_level_);
        words_[0] = node::uniform(CellState::Unknown);
      }
      return;
    }
    if (empty()) {  // nothing to keep: the cube becomes the root
      ++version_;
      root_level_ = level;
      base_ = c;
    } else {
      growToCover(x, y, z, level);
    }
  }
  const std::uint64_t cells = node::cellsIn(1, level);
  const auto add = [&](NodeWord w) {
    if (state != CellState::Unknown) counts_[std::size_t(state)] += cells;
    value_leaves_ += node::hasValues(w);
  };
  ++version_;
  if (level == root_level_) {  // the cube is the root
    releaseSubtree(0, root_level_);
    words_[0] = cube;
    add(cube);
    return;
  }
  std::size_t path[kMaxLevel + 1];
  path[root_level_] = 0;
  unsigned l = root_level_;
  for (; l > level + 1 && !node::isBitmap(words_[path[l]]); --l)
    path[l - 1] = node::childOffset(words_[path[l]], c.octant(l));
  const NodeWord top = words_[path[l]];
  if (node::isBitmap(top)) {
    // From this bitmap word down to the cube's parent each level takes a block, and so does the parent
    // when it holds other values than the cube.
    const NodeWord octant = node::octantWord(top, c.octant(l));
    if (octant == cube) return;  // inside such a cube
    const NodeWord parent = l > level + 1 ? octant : top;
    reserveBlocks(l - level - 1 + ((parent & kValueBits) != (cube & kValueBits) ? 1 : 0));
  }
  for (; l > level + 1; --l) path[l - 1] = splitWord(path[l]) + c.octant(l);
  const unsigned o = c.octant(level + 1);
  const NodeWord parent = words_[path[level + 1]];
  if (node::isBitmap(parent) && (parent & kValueBits) == (cube & kValueBits)) {  // the cube is an octant
    const CellState old = node::state(parent, o);
    if (old != CellState::Unknown) counts_[std::size_t(old)] -= cells;
    if (state != CellState::Unknown) counts_[std::size_t(state)] += cells;
    words_[path[level + 1]] = node::withState(parent, o, state);
    const NodeWord now = words_[path[level + 1]];
    if (node::isUniform(now) || node::isValueUniform(now)) collapseFrom(path, level + 1);
    return;
  }
  // A parent holding other values than the cube's: its octants become words, the cube one of them.
  const std::size_t first = node::isBitmap(parent) ? splitWord(path[level + 1]) : node::childBase(parent);
  path[level] = first + o;
  releaseSubtree(path[level], level);
  words_[path[level]] = cube;
  add(cube);
  collapseFrom(path, level);
}

void FastOctTree::releaseSubtree(std::size_t at, unsigned level) {
  const NodeWord w = words_[at];
  if (node::isBitmap(w)) {
    for (CellState s : {CellState::Free, CellState::Occupied})
      counts_[std::size_t(s)] -= node::cellsIn(node::popcount(node::octantMask(w, s)), level - 1);
    values_.release(w, at);
    value_leaves_ -= node::hasValues(w);
    return;
  }
  for (unsigned o = 0; o < 8; ++o) releaseSubtree(node::childOffset(w, o), level - 1);
  freeBlock(node::block(w));
}

void FastOctTree::shrinkToFit() {
  compactPool();
  words_.shrink_to_fit();
  values_.shrinkToFit(value_leaves_ == 0);  // no leaf names a palette entry then
}

void FastOctTree::compactPool() {
  const std::uint32_t end = std::uint32_t(1 + live_blocks_);  // block 0 holds the root
  if (free_blocks_ == 0) return;
  std::vector<std::uint32_t> slots;  // the free blocks below `end`: as many as live blocks past it
  for (std::uint32_t b = free_head_; b != kNoBlock; b = words_[std::size_t(b) * 8])
    if (b < end) slots.push_back(b);
  // Parents first: a block moved down takes its children's references along, which are then followed.
  auto walk = [&](auto& self, std::size_t at) -> void {
    if (node::isBitmap(words_[at])) return;
    std::uint32_t b = node::block(words_[at]);
    if (b >= end) {
      const std::uint32_t to = slots.back();
      slots.pop_back();
      std::copy_n(words_.begin() + std::ptrdiff_t(b) * 8, 8, words_.begin() + std::ptrdiff_t(to) * 8);
      values_.poolMoved(std::size_t(b) * 8, std::size_t(to) * 8, 8);
      words_[at] = node::reference(to);
      b = to;
    }
    for (unsigned o = 0; o < 8; ++o) self(self, std::size_t(b) * 8 + o);
  };
  walk(walk, 0);
  words_.resize(std::size_t(end) * 8);
  values_.poolResized(words_.size());
  free_head_ = kNoBlock;
  free_blocks_ = 0;
  ++version_;
}

void FastOctTree::setMaxMemoryBytes(std::size_t bytes) {
  max_bytes_ = bytes;
}

void FastOctTree::reserveBlocks(std::size_t n) {
  if (n <= free_blocks_) return;
  const std::size_t fresh = n - free_blocks_;
  const std::size_t blocks = words_.size() / 8 + fresh;
  const std::size_t bytes = blocks * 8 * sizeof(NodeWord) * (values_.indexed() ? 2 : 1) + values_.rowBytes();
  if (bytes > max_bytes_)
    throw MemoryLimitError("pcl::fot::FastOctTree: the pool would need " + std::to_string(bytes) +
                           " bytes, beyond the cap of " + std::to_string(max_bytes_) + " bytes");
  if (blocks > node::kMaxBlocks)
    throw MemoryLimitError("pcl::fot::FastOctTree: the pool would exceed 2^31 blocks");
  if (blocks * 8 > words_.capacity()) {
    const std::size_t cap_words = max_bytes_ / sizeof(NodeWord);
    words_.reserve(std::max(blocks * 8, std::min(words_.capacity() * 2, cap_words)));
    values_.poolReserved(words_.capacity());
  }
}

std::uint32_t FastOctTree::allocBlock() {
  ++live_blocks_;
  if (free_head_ != kNoBlock) {
    const std::uint32_t block = free_head_;
    free_head_ = words_[std::size_t(block) * 8];
    --free_blocks_;
    return block;
  }
  const std::uint32_t block = std::uint32_t(words_.size() / 8);
  words_.resize(words_.size() + 8);  // within the capacity reserveBlocks made
  values_.poolResized(words_.size());
  return block;
}

void FastOctTree::freeBlock(std::uint32_t block) {
  words_[std::size_t(block) * 8] = free_head_;
  free_head_ = block;
  ++free_blocks_;
  --live_blocks_;
}

void FastOctTree::growToCover(std::uint32_t x, std::uint32_t y, std::uint32_t z, unsigned level) {
  ++version_;
  if (empty()) {  // nothing to keep: re-anchor a small root at the key
    root_level_ = 1;
    base_ = TreeCoord(x, y, z).corner(1);
    return;
  }
  const std::uint32_t far = (std::uint32_t(1) << level) - 1;  // the cube's corners differ in these bits only
  const unsigned target = tree_coord::commonLevel(((x | far) ^ base_[0]) | (x ^ base_[0]),
                                                  ((y | far) ^ base_[1]) | (y ^ base_[1]),
                                                  ((z | far) ^ base_[2]) | (z ^ base_[2]));
  // Growth takes a block per level, but a uniform root folds into its parent's bitmap for free. The write
  // then builds the path from the new root down to the cube's parent, below the new root's block if there
  // is one. Reserving both first keeps a refused write from leaving the root grown.
  const bool folds = node::isUniform(words_[0]) || node::isValueUniform(words_[0]);
  const std::size_t growth = target - root_level_ - (folds ? 1 : 0);
  const std::size_t path = target > level + 1 ? target - level - (growth > 0 ? 2 : 1) : 0;
  reserveBlocks(growth + path);
  while (root_level_ < target) {
    const NodeWord root = words_[0];
    const unsigned octant = base_.octant(root_level_ + 1);
    if (node::isUniform(root) || node::isValueUniform(root)) {
      // A uniform root folds straight into one octant of its parent, its value with it: no block needed.
      words_[0] = node::withState(node::uniform(CellState::Unknown), octant, node::state(root, 0)) |
                  (root & kValueBits);
    } else {
      const std::uint32_t block = allocBlock();
      const std::size_t first = std::size_t(block) * 8;
      std::fill_n(words_.begin() + first, 8, node::uniform(CellState::Unknown));
      words_[first + octant] = root;
      if (node::hasValueRow(root)) values_.poolMoved(0, first + octant, 1);
      words_[0] = node::reference(block);
    }
    ++root_level_;
    base_ = base_.corner(root_level_);
  }
}

void FastOctTree::expandTo(std::size_t* path, unsigned level, std::uint32_t x, std::uint32_t y,
                           std::uint32_t z) {
  reserveBlocks(level - 1);
  ++version_;
  for (; level > 1; --level) path[level - 1] = splitWord(path[level]) + tree_coord::octant(x, y, z, level);
}

std::size_t FastOctTree::splitWord(std::size_t at) {
  const NodeWord w = words_[at];
  const std::uint32_t block = allocBlock();
  const std::size_t first = std::size_t(block) * 8;
  for (unsigned o = 0; o < 8; ++o) words_[first + o] = node::octantWord(w, o);
  if (node::hasValues(w)) value_leaves_ += node::popcount(~node::octantMask(w, CellState::Unknown)) - 1;
  words_[at] = node::reference(block);
  return first;
}

NodeWord FastOctTree::foldedBlock(std::size_t first) const {
  NodeWord folded = node::kBitmapTag, value = 0;
  bool settled = false;
  for (unsigned o = 0; o < 8; ++o) {
    const NodeWord w = words_[first + o];
    if (node::isValueUniform(w)) {
      if (value != 0 && (w & kValueBits) != value) return 0;
      value = w & kValueBits;
    } else if (node::isUniform(w)) {
      settled = settled || node::uniformState(w) != CellState::Unknown;
    } else {
      return 0;
    }
    folded = node::withState(folded, o, node::state(w, 0));
  }
  // A flagged word's known octants all hold its one value: settled cubes do not join it.
  return settled && value != 0 ? 0 : folded | value;
}

NodeWord FastOctTree::foldBlock(std::size_t parent_at, std::size_t first) {
  const NodeWord folded = foldedBlock(first);
  if (folded == 0) return 0;
  for (unsigned o = 0; o < 8; ++o) value_leaves_ -= node::hasValues(words_[first + o]);
  value_leaves_ += node::hasValues(folded);
  freeBlock(std::uint32_t(first / 8));
  words_[parent_at] = folded;
  ++version_;
  return folded;
}

void FastOctTree::foldSubtree(std::size_t at) {
  const NodeWord w = words_[at];
  if (node::isBitmap(w)) return;
  for (unsigned o = 0; o < 8; ++o) foldSubtree(node::childOffset(w, o));
  foldBlock(at, node::childBase(w));
}

unsigned FastOctTree::collapseFrom(const std::size_t* path, unsigned level) {
  while (level < root_level_) {
    const NodeWord parent = foldBlock(path[level + 1], path[level] & ~std::size_t(7));
    if (parent == 0) return level;
    ++level;
    if (!node::isUniform(parent) && !node::isValueUniform(parent)) return level;
  }
  return level;
}

void FastOctTree::clear() {
  std::vector<NodeWord>(8, 0).swap(words_);
  words_[0] = node::uniform(CellState::Unknown);
  root_level_ = 1;
  base_ = TreeCoord();
  free_head_ = kNoBlock;
  free_blocks_ = 0;
  live_blocks_ = 0;
  counts_ = {0, 0, 0};
  values_.clear();
  value_leaves_ = 0;
  ++version_;
}

std::size_t FastOctTree::offsetOf(const NodeView& n) const {
  std::size_t at = 0;
  for (NodeView v = root(); v.level > n.level && !v.isBitmap();
       v = v.child(words_.data(), n.corner.octant(v.level)))
    at = v.childOffset(n.corner.octant(v.level));
  return at;
}

NodeView FastOctTree::contentRoot() const {
  NodeView n = root();
  while (n.level > 1) {
    unsigned only = 8;
    for (unsigned o = 0; o < 8; ++o) {
      if (NodeView::childWord(words_.data(), n.word, o) == node::uniform(CellState::Unknown)) continue;
      if (only != 8) return n;
      only = o;
    }
    if (only == 8) return n;  // empty
    // A flagged word's octant is a cube of its value: a word of its own.
    const NodeWord w = n.isBitmap() ? node::octantWord(n.word, only) : words_[n.childOffset(only)];
    n = NodeView{w, n.level - 1, n.corner.child(only, n.level - 1)};
  }
  return n;
}

namespace {

bool sameSubtree(const FastOctTree& a, std::size_t at_a, NodeWord wa, const FastOctTree& b, std::size_t at_b,
                 NodeWord wb) {
  if (node::isBitmap(wa) || node::isBitmap(wb)) {
    // Palette indices depend on the order values appeared: compare the values instead.
    if ((wa & ~node::kPaletteMask) != (wb & ~node::kPaletteMask)) return false;
    if (!node::hasValues(wa)) return true;
    for (unsigned o = 0; o < 8; ++o) {
      const float va = a.wordValue(wa, at_a, o), vb = b.wordValue(wb, at_b, o);
      if (std::memcmp(&va, &vb, sizeof va) != 0) return false;
    }
    return true;
  }
  for (unsigned o = 0; o < 8; ++o) {
    const std::size_t ca = node::childOffset(wa, o), cb = node::childOffset(wb, o);
    if (!sameSubtree(a, ca, a.words()[ca], b, cb, b.words()[cb])) return false;
  }
  return true;
}

}  // namespace

bool FastOctTree::operator==(const FastOctTree& other) const {
  if (grid_ != other.grid_ || model_ != other.model_ || counts_ != other.counts_) return false;
  if (empty() || other.empty()) return empty() == other.empty();
  const NodeView a = contentRoot(), b = other.contentRoot();
  // A content root at level 1 is the root word, at offset 0; the offsets matter only for leaves.
  return a.level == b.level && a.corner == b.corner &&
         sameSubtree(*this, offsetOf(a), a.word, other, other.offsetOf(b), b.word);
}

}  // namespace fot
}  // namespace pcl
