#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <type_traits>

#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

[[noreturn]] void throwKeyOutOfRange(const char* where, const Key& key);

/**
 * LineBurstAccess (paper §II): a handle that remembers the root-to-leaf path of its last access and starts
 * the next one at the deepest common ancestor of the old and new keys. Consecutive points of a range image
 * and consecutive cells of a ray share all but the lowest levels, so most accesses touch one or two words.
 *
 * The path holds pool offsets, which survive pool growth. Any structural change made elsewhere bumps the
 * tree's structure version, and the accessor then restarts from the root; changes it makes itself keep
 * its path valid. With line_burst = false every access starts at the root; results are identical.
 *
 * One accessor per thread: an accessor is cheap to make and is not shared.
 */
template <typename TreeT>
class BasicAccessor {
 public:
  explicit BasicAccessor(TreeT& tree, bool line_burst = true) : tree_(&tree), line_burst_(line_burst) {}

  bool lineBurst() const { return line_burst_; }
  TreeT& tree() const { return *tree_; }

  CellState getCell(const Key& key) {
    const TreeCoord c(key);
    // Keys beyond the range map to coordinates no write can reach, so they read as Unknown.
    if (!locate(c[0], c[1], c[2])) return CellState::Unknown;
    return node::state(tree_->words()[path_[bottom_]], c.octant(bottom_));
  }

  /**
   * Writes one cell. Throws std::out_of_range for keys outside [kMinKey, kMaxKey] and MemoryLimitError
   * past the pool cap. Returns what setValidCell() returns.
   */
  unsigned setCell(const Key& key, CellState state) {
    if (!isValidKey(key)) throwKeyOutOfRange("pcl::fot::Accessor::setCell", key);
    return setValidCell(key, state);
  }

  /** setCell for a key the caller has already checked with isValidKey(). */
  unsigned setValidCell(const Key& key, CellState state) {
    return setValidLeafCells(key, 1u << TreeCoord(key).octant(1), state);
  }

  /**
   * Writes `state` into the cells `mask` selects (bit i: octant i) of the 2×2×2 leaf that holds `key`, a
   * valid key: one access for a run of neighbouring cells, as a ray produces them.
   *
   * If those cells all held `state` already, returns the level l of a uniform cube around `key` that holds
   * `state` everywhere (an aligned cube of 2^l cells per axis in tree coordinates; 0 for a lone cell). A
   * writer sweeping through space, such as a ray, may then skip the rest of that cube: LineBurstAccess at
   * its limit, the last visited node answering for the next cells. Returns 0 when anything changed, and
   * always without LineBurstAccess.
   */
  unsigned setValidLeafCells(const Key& key, std::uint32_t mask, CellState state) {
    static_assert(!std::is_const<TreeT>::value, "a ConstAccessor cannot write");
    if (mask == 0) return 0;
    const TreeCoord c(key);
    const std::uint32_t x = c[0], y = c[1], z = c[2];
    if (!locate(x, y, z)) {
      if (state == CellState::Unknown) return 0;  // erasing outside the extent changes nothing
      tree_->growToCover(x, y, z, 0);
      locate(x, y, z);
    }
    NodeWord w = tree_->words()[path_[bottom_]];
    if (bottom_ > 1) {
      if (node::octantWord(w, c.octant(bottom_)) == node::uniform(state))
        return line_burst_ ? bottom_ - 1 : 0;
      tree_->expandTo(path_, bottom_, x, y, z);  // the cube holds another state: some cell changes
      bottom_ = 1;
      w = tree_->words()[path_[1]];
    }
    if (node::hasValues(w)) {  // values, or a cube of one value split down to this leaf
      bottom_ = tree_->setLeafStates(path_, mask, state);
      version_ = tree_->structureVersion();
      return 0;
    }
    const NodeWord updated = node::withStates(w, mask, state);
    if (updated == w) return line_burst_ && node::isUniform(w) ? 1 : 0;
    writeLeaf(updated);
    return 0;
  }

  void eraseCell(const Key& key) { setCell(key, CellState::Unknown); }

  /** The cell's log-odds; NaN for an unknown cell. */
  float getLogOdds(const Key& key) {
    const TreeCoord c(key);
    if (!locate(c[0], c[1], c[2])) return FastOctTree::kUnknownValue;
    return tree_->leafValue(path_[bottom_], c.octant(bottom_));
  }

  /**
   * One scan's evidence for the 2×2×2 leaf that holds `key`, a valid key: a miss for the cells `miss`
   * selects and a hit for those of `hit` (disjoint masks), by OctoMap's rule (SensorModel). Returns what
   * setValidLeafCells() returns: a level l > 0 when nothing changed because the uniform cube of level l
   * around the key is settled in the direction of every update, so a sweep may skip it.
   */
  unsigned updateLeaf(const Key& key, std::uint32_t miss, std::uint32_t hit) {
    static_assert(!std::is_const<TreeT>::value, "a ConstAccessor cannot write");
    const TreeCoord c(key);
    const std::uint32_t x = c[0], y = c[1], z = c[2];
    const NodeWord w = reach(x, y, z);
    if (bottom_ > 1) {
      const CellState s = node::state(w, c.octant(bottom_));
      const bool settled = !node::hasValues(w);  // else a cube of one value between the clamps
      if (settled && ((s == CellState::Free && hit == 0) || (s == CellState::Occupied && miss == 0)))
        return line_burst_ ? bottom_ - 1 : 0;
      expand(x, y, z);
    } else if (!node::hasValues(w) && (node::octantMask(w, CellState::Free) & miss) == miss &&
               (node::octantMask(w, CellState::Occupied) & hit) == hit) {
      return line_burst_ && node::isUniform(w) ? 1 : 0;
    }
    const SensorModel& m = tree_->getSensorModel();
    float update[8];
    for (unsigned o = 0; o < 8; ++o) update[o] = (hit >> o) & 1u ? m.hitLogOdds() : m.missLogOdds();
    bottom_ = tree_->updateLeaf(path_, miss | hit, update);
    version_ = tree_->structureVersion();
    return 0;
  }

  /** missBlock's answer when the block holds more than one value: nothing was written. */
  static constexpr unsigned kByLeaves = ~0u;

  /**
   * One scan's miss for each of the 64 cells of the 4×4×4 block whose lowest cell is `key` (a valid key,
   * tree coordinates multiples of 4): by OctoMap's rule, or made free (`log_odds` false). Where the tree
   * holds the block inside one cube (settled, unknown or of one value), its cells change alike and the
   * block is written as one cube, not leaf by leaf. Returns what updateLeaf() returns, or kByLeaves.
   */
  unsigned missBlock(const Key& key, bool log_odds) {
    static_assert(!std::is_const<TreeT>::value, "a ConstAccessor cannot write");
    const TreeCoord c(key);
    const NodeWord w = reach(c[0], c[1], c[2]);
    if (bottom_ < 3) return kByLeaves;
    if (!node::hasValues(w) && node::state(w, c.octant(bottom_)) == CellState::Free)
      return line_burst_ ? bottom_ - 1 : 0;
    if (log_odds) {
      float v = tree_->leafValue(path_[bottom_], c.octant(bottom_));
      tree_->getSensorModel().updateNode(v, tree_->getSensorModel().missLogOdds());
      tree_->setCubeLogOdds(c, 2, v);
    } else {
      tree_->setCube(c, 2, CellState::Free);
    }
    return 0;
  }

  /** FastOctTree::updateLogOdds for a valid key, with a finite update. */
  void updateCell(const Key& key, float update) {
    const float update8[8] = {update, update, update, update, update, update, update, update};
    updateLeafCells(key, 1u << TreeCoord(key).octant(1), update8);
  }

  /**
   * updateCell for the cells `mask` selects of the 2×2×2 leaf holding `key`, a valid key: cell o by
   * update[o], with one walk for the leaf.
   */
  void updateLeafCells(const Key& key, std::uint32_t mask, const float* update) {
    static_assert(!std::is_const<TreeT>::value, "a ConstAccessor cannot write");
    if (!isValidKey(key)) throwKeyOutOfRange("pcl::fot::Accessor::updateCell", key);
    const TreeCoord c(key);
    reach(c[0], c[1], c[2]);
    if (bottom_ > 1) {
      // A cube of one value stays whole unless an update can move it.
      const float before = tree_->leafValue(path_[bottom_], c.octant(bottom_));
      bool moves = false;
      for (std::uint32_t m = mask; m != 0; m &= m - 1) {
        float v = before;
        moves |= tree_->getSensorModel().updateNode(v, update[__builtin_ctz(m)]);
      }
      if (!moves) return;
      expand(c[0], c[1], c[2]);
    }
    bottom_ = tree_->updateLeaf(path_, mask, update);
    version_ = tree_->structureVersion();
  }

  /** FastOctTree::setLogOdds for a valid key, with a finite value. */
  void setLogOdds(const Key& key, float value) {
    static_assert(!std::is_const<TreeT>::value, "a ConstAccessor cannot write");
    if (!isValidKey(key)) throwKeyOutOfRange("pcl::fot::Accessor::setLogOdds", key);
    const TreeCoord c(key);
    reach(c[0], c[1], c[2]);
    if (bottom_ > 1) expand(c[0], c[1], c[2]);
    bottom_ = tree_->setLeafValue(path_, c.octant(1), value);
    version_ = tree_->structureVersion();
  }

  /**
   * Locates the bitmap word whose octant holds `key` and returns its level, or 0 when the key lies outside
   * the root. Afterwards pathOffset(l) is the pool offset of the level-l word on the way down, for every
   * level from the returned one up to the root. Search algorithms walk back up this path.
   */
  unsigned locatePath(const Key& key) {
    const TreeCoord c(key);
    return locate(c[0], c[1], c[2]) ? bottom_ : 0u;
  }
  std::size_t pathOffset(unsigned level) const { return path_[level]; }

  /** Forgets the cached path; the next access starts at the root. */
  void reset() { version_ = kNoPath; }

 private:
  static constexpr std::uint64_t kNoPath = ~std::uint64_t(0);

  /** Locates (x, y, z), growing the root to cover it first, and returns the bitmap word holding it. */
  NodeWord reach(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    if (!locate(x, y, z)) {
      tree_->growToCover(x, y, z, 0);
      locate(x, y, z);
    }
    return tree_->words()[path_[bottom_]];
  }

  /**
   * Expands the uniform word at the end of the path down to the leaf of (x, y, z), with room for its values
   * in the grown pool: past the cap, nothing changes.
   */
  void expand(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    tree_->values_.reserveRow(tree_->pool(), 8 * (bottom_ - 1));
    tree_->expandTo(path_, bottom_, x, y, z);
    bottom_ = 1;
  }

  /** Replaces the leaf word at the end of the path: the tree keeps its counts and canonical form. */
  void writeLeaf(NodeWord updated) {
    bottom_ = tree_->writeLeaf(path_, updated);
    version_ = tree_->structureVersion();
  }

  /** Finds the bitmap word holding (x, y, z): path_[bottom_]. False outside the root. */
  bool locate(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    const TreeT& t = *tree_;
    unsigned level;
    if (line_burst_ && version_ == t.structureVersion()) {
      level = tree_coord::commonLevel(x ^ x_, y ^ y_, z ^ z_);
      if (level > t.getDepth()) return false;
      if (level < bottom_) level = bottom_;
    } else {
      const TreeCoord base = t.root().corner;
      if (((x ^ base[0]) | (y ^ base[1]) | (z ^ base[2])) >> t.getDepth()) return false;
      level = t.getDepth();
      path_[level] = 0;
      bottom_ = level;
      version_ = t.structureVersion();
    }
    const NodeWord* words = t.words();
    std::size_t at = path_[level];
    if (level > bottom_) {
      // The new node one level down is a sibling of the cached one: address it without a load.
      at = (path_[level - 1] & ~std::size_t(7)) | tree_coord::octant(x, y, z, level);
      path_[--level] = at;
    }
    NodeWord w = words[at];
    while (!node::isBitmap(w)) {
      at = node::childOffset(w, tree_coord::octant(x, y, z, level));
      path_[--level] = at;
      w = words[at];
    }
    bottom_ = level;
    x_ = x;
    y_ = y;
    z_ = z;
    return true;
  }

  TreeT* tree_;
  bool line_burst_;
  std::uint64_t version_ = kNoPath;
  std::uint32_t x_ = 0, y_ = 0, z_ = 0;  // last key, tree coordinates
  unsigned bottom_ = 1;                  // level of the bitmap word at the end of the path
  std::size_t path_[kMaxLevel + 1];      // path_[l]: pool offset of the level-l word on the path
};

using Accessor = BasicAccessor<FastOctTree>;
using ConstAccessor = BasicAccessor<const FastOctTree>;

}  // namespace fot
}  // namespace pcl
