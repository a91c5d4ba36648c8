#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <pcl_fot/tree/cell_grid.h>
#include <pcl_fot/tree/key.h>
#include <pcl_fot/tree/leaf_values.h>
#include <pcl_fot/tree/node_view.h>
#include <pcl_fot/tree/node_word.h>
#include <pcl_fot/tree/sensor_model.h>

namespace pcl {
namespace fot {

/** What a batch insertion did with its input. */
struct InsertStats {
  std::size_t inserted = 0;      ///< points or keys written
  std::size_t non_finite = 0;    ///< NaN or Inf points, skipped
  std::size_t out_of_range = 0;  ///< points or keys beyond the key range, skipped
};

/** A uniform cube of 2^level cells per axis whose lowest corner is `min_key`. A voxel has level 0. */
struct Region {
  Key min_key;
  unsigned level;
  CellState state;
};

template <typename TreeT>
class BasicAccessor;

/**
 * The FastOctTree of Poppinga et al. (SSRR 2007): an occupancy octree of 4-byte node words.
 *
 * Cells are addressed by integer keys on a CellGrid. The root is one word; every other word lives in a
 * block of 8 siblings in a pool, and blocks are recycled through a free list. Uniform octants collapse
 * into one bitmap word of their parent after every write, so the tree is always in canonical form: its
 * shape depends only on its cells, never on the order of writes. The root grows on demand to cover
 * new keys in any direction.
 *
 * Every cell also has a log-odds, as in OctoMap (SensorModel). A cell at a clamp is settled and is its
 * state alone: free at the lower clamp, occupied at the upper. A leaf with a cell between the clamps is
 * flagged (node::kValueFlag) and keeps its values beside the pool (LeafValues); cubes whose cells share one
 * value between the clamps fold into one flagged word at any level, as OctoMap prunes equal values. States
 * are the values thresholded, so every reader of states sees the thresholded map. Binary writes (setCell,
 * the paper's rule) settle the cells they write.
 *
 * Repeated access should go through an Accessor (LineBurstAccess, see accessor.h). Const members are
 * safe to call from many threads at once; writes need exclusive access.
 */
class FastOctTree {
 public:
  using Ptr = std::shared_ptr<FastOctTree>;
  using ConstPtr = std::shared_ptr<const FastOctTree>;

  explicit FastOctTree(double resolution, double origin_x = 0.0, double origin_y = 0.0,
                       double origin_z = 0.0);
  explicit FastOctTree(const CellGrid& grid);

  const CellGrid& getGrid() const { return grid_; }
  double getResolution() const { return grid_.resolution(); }

  const SensorModel& getSensorModel() const { return model_; }
  /**
   * Throws std::logic_error if the map holds cells and the clamps or the threshold change: its settled
   * cells are defined by them. The hit and miss probabilities may change at any time.
   */
  void setSensorModel(const SensorModel& model);
  /** The rule scans use unless ScanOptions says otherwise; Binary by default, as before the log-odds. */
  UpdateRule getUpdateRule() const { return rule_; }
  void setUpdateRule(UpdateRule rule) { rule_ = rule; }

  /** The cell's log-odds; NaN for an unknown cell. */
  float getLogOdds(const Key& key) const;
  /** The cell's occupancy probability, OctoMap's probability(log-odds); NaN for an unknown cell. */
  double getProbability(const Key& key) const;
  /**
   * OctoMap's updateNode(key, update): the log-odds plus `update`, clamped, unless the value has reached the
   * clamp the update heads for. An unknown cell starts at 0. Throws std::out_of_range for an invalid key and
   * std::invalid_argument for a non-finite update.
   */
  void updateLogOdds(const Key& key, float update);
  /** Sets the cell's log-odds as given (OctoMap's setNodeValue); throws as updateLogOdds for bad input. */
  void setLogOdds(const Key& key, float log_odds);
  /** Known cells whose log-odds lies strictly between the clamps. */
  std::uint64_t getUnsettledCount() const;
  /** OctoMap's toMaxLikelihood(): every cell settles at the clamp of its state, and the values go. */
  void toMaxLikelihood();

  /**
   * Adds the evidence of `other` into this map: every cell `other` knows gets its log-odds as an
   * update (updateLogOdds). Throws std::invalid_argument, changing nothing, if the grids differ.
   */
  void merge(const FastOctTree& other);

  /** Unknown outside the mapped extent. */
  CellState getCell(const Key& key) const;
  /** Throws std::out_of_range for a key outside [kMinKey, kMaxKey]. */
  void setCell(const Key& key, CellState state);
  void eraseCell(const Key& key) { setCell(key, CellState::Unknown); }

  /** Unknown beyond the representable range; throws std::invalid_argument for NaN or Inf. */
  CellState getCellAtPoint(double x, double y, double z) const;
  /** Throws std::invalid_argument for NaN or Inf and std::out_of_range beyond the key range. */
  void setCellAtPoint(double x, double y, double z, CellState state);
  void eraseCellAtPoint(double x, double y, double z) { setCellAtPoint(x, y, z, CellState::Unknown); }

  /**
   * Sets every cell of the key box [lo, hi] (inclusive on each axis) to `state`. The box is split into
   * maximal aligned cubes, each written as one word, so time and memory grow with the box's surface, not
   * its volume (setMaxMemoryBytes bounds them). Throws std::out_of_range for keys beyond the range, and
   * std::invalid_argument for an empty box (lo above hi on an axis) or one of 2^60 cells or more (the cell
   * counts are 64-bit). MemoryLimitError past the pool cap leaves the cubes written until then.
   */
  void setBox(const Key& lo, const Key& hi, CellState state);
  /**
   * Sets every cell of the key box [lo, hi] to `log_odds` (NaN: unknown), whole cubes at once: a cube of
   * one value between the clamps is one word, as a settled one is (forEachLogOdds visits such cubes).
   * Throws as setBox, and std::invalid_argument for an infinite value.
   */
  void setBoxLogOdds(const Key& lo, const Key& hi, float log_odds);

  /** Writes every valid key; invalid keys are skipped and counted. */
  InsertStats insertKeys(const Key* keys, std::size_t count, CellState state = CellState::Occupied,
                         bool line_burst = true);
  /**
   * Writes the cell of every point. Point i's x, y, z are the three floats at byte offset i * stride_bytes,
   * which fits the layout of any PCL point type. NaN, Inf and out-of-range points are skipped and counted.
   */
  InsertStats insertPoints(const float* xyz, std::size_t count, std::size_t stride_bytes,
                           CellState state = CellState::Occupied, bool line_burst = true);

  /**
   * Visits every maximal uniform known cube (a uniform word, or a cube of one value) in Morton order:
   * visit(const Region&), which may return false to stop the walk.
   */
  template <typename Visitor>
  void forEachRegion(Visitor&& visit) const;
  /** As forEachRegion, but only the regions that overlap the key box [lo, hi] (inclusive), whole. */
  template <typename Visitor>
  void forEachRegionInBox(const Key& lo, const Key& hi, Visitor&& visit) const;
  /** As forEachRegion, but only the regions that reach outside the key box [lo, hi] (inclusive), whole. */
  template <typename Visitor>
  void forEachRegionOutsideBox(const Key& lo, const Key& hi, Visitor&& visit) const;
  /** Visits every cell holding `state` (other than Unknown) in Morton order: visit(const Key&). */
  template <typename Visitor>
  void forEachCell(CellState state, Visitor&& visit) const;
  /**
   * Visits every known cell with its log-odds in Morton order, without a lookup per cell: visit(const
   * Region&, float), which may return false to stop the walk. A cube of one value comes whole: a settled
   * cube with its clamp, a folded cube between the clamps with its float; other cells come alone (level 0).
   * Exporting or comparing a map reads it this way.
   */
  template <typename Visitor>
  void forEachLogOdds(Visitor&& visit) const;

  std::uint64_t getOccupiedCount() const { return counts_[std::size_t(CellState::Occupied)]; }
  std::uint64_t getFreeCount() const { return counts_[std::size_t(CellState::Free)]; }
  bool empty() const { return words_[0] == node::uniform(CellState::Unknown); }

  /** Blocks of 8 words in use. */
  std::size_t getBlockCount() const { return live_blocks_; }
  /** Node words in use: the root plus 8 per block. */
  std::size_t getNodeCount() const { return 1 + 8 * live_blocks_; }
  /**
   * Leaves whose cells carry different values, each with a row: of 8 palette indices (8 bytes) when the
   * palette's first 255 values hold them, else of 8 floats. A leaf whose known cells hold one value takes
   * none: its word names the value in a palette of up to 16382 values (LeafValues).
   */
  std::size_t getValueRowCount() const { return values_.rowCount(); }
  /** Words whose cells carry values (a cell between the clamps), by palette or by row, at any level. */
  std::size_t getValueLeafCount() const { return value_leaves_; }
  /** Every byte the tree holds: the object, the pool and the values, free blocks and rows included. */
  std::size_t getMemoryBytes() const { return sizeof(*this) + words_.capacity() * 4 + values_.bytes(); }
  /** Root level: the root spans 2^depth cells per axis. */
  unsigned getDepth() const { return root_level_; }

  /**
   * Caps the pool. A write that would need more gets MemoryLimitError, and the tree stays as it was.
   * The default is no cap.
   */
  void setMaxMemoryBytes(std::size_t bytes);
  std::size_t getMaxMemoryBytes() const { return max_bytes_; }

  /**
   * Gives back what the map does not use: the blocks freed when cells settled, folded or were erased (the
   * live blocks move to the front of the pool), the room the pool and the index of values keep for growth
   * (they double as they grow), and the palette once no leaf carries values, so a map whose cells have all
   * settled costs what the binary map of the same cells costs. The next growth copies them; call it when a
   * map is done, or between batches of scans.
   */
  void shrinkToFit();

  /** Removes every cell and releases the pool. */
  void clear();

  /** Same grid, sensor model, and the same state and log-odds in every cell. */
  bool operator==(const FastOctTree& other) const;
  bool operator!=(const FastOctTree& other) const { return !(*this == other); }

  /**
   * The tree as the .fot format stores it (io/fot_file.h). The root is the smallest cube holding every
   * known cell. Block 0 holds the root word and seven zero words; the referenced blocks follow in
   * depth-first pre-order, each reference renumbered. Equal trees give equal pools, word for word.
   */
  struct CanonicalPool {
    unsigned root_level = 1;
    TreeCoord root_base;
    std::vector<NodeWord> words;
    /** The 8 log-odds of each flagged word, in pre-order; NaN for unknown cells. */
    std::vector<float> values;
    SensorModel model;
  };
  CanonicalPool canonicalPool() const;

  /**
   * The tree a canonical pool describes, checked in full before it is built: the root's level and
   * alignment, block 0's padding, every reference (to the next block in pre-order, never from level 1, no
   * block left over), every bitmap (spare bits clear, no invalid state), canonical form (no block of 8
   * uniform words, a minimal root), every known cell within the key range, every flagged word's values
   * (NaN exactly where the state is unknown, finite and thresholded to the state elsewhere, one unsettled
   * at least, one value above the leaves), and the pool's size against max_bytes. Throws
   * std::invalid_argument naming the first violation. Blocks of cubes of one value, which pools written
   * before such cubes folded spell out, are folded.
   */
  static FastOctTree fromCanonicalPool(const CellGrid& grid, CanonicalPool pool,
                                       std::size_t max_bytes = std::numeric_limits<std::size_t>::max());

  /**
   * Low-level read access, for algorithms built on the tree (search, ψ, io): the root node, walked with
   * NodeView::child() over words(). The root's pool offset is 0.
   */
  NodeView root() const { return NodeView{words_[0], root_level_, base_}; }
  const NodeWord* words() const { return words_.data(); }
  /**
   * The smallest node holding every known cell: the root, descended while only one octant holds anything
   * (into a bitmap's octant as node::octantWord gives it). Canonical form holds below the root, so two trees
   * with the same cells reach the same node.
   */
  NodeView contentRoot() const;
  std::size_t poolWords() const { return words_.size(); }
  /** The pool offset of the word of a node below references only, such as contentRoot(): found from the root
   * down the node's corner. */
  std::size_t offsetOf(const NodeView& n) const;
  /**
   * The log-odds of octant o of the bitmap word at pool offset `at`: a cell's for a leaf, a whole octant's
   * above.
   */
  float leafValue(std::size_t at, unsigned o) const { return wordValue(words_[at], at, o); }
  /**
   * As leafValue, for the bitmap word w of a node view: contentRoot() may be a cube of one value that is an
   * octant of its parent's word, whose offset offsetOf() then gives (only a leaf's row needs the offset).
   */
  float wordValue(NodeWord w, std::size_t at, unsigned o) const {
    if (!node::hasValues(w) || node::state(w, o) == CellState::Unknown)
      return settledValue(node::state(w, o));
    return values_.value(w, at, o);
  }
  /** The log-odds a settled cell of this state holds; NaN for Unknown. */
  float settledValue(CellState s) const {
    return s == CellState::Free ? model_.clampMinLogOdds()
                                : (s == CellState::Occupied ? model_.clampMaxLogOdds() : kUnknownValue);
  }
  static constexpr float kUnknownValue = std::numeric_limits<float>::quiet_NaN();
  /** Changes whenever blocks are allocated, freed or re-linked; accessors restart from the root then. */
  std::uint64_t structureVersion() const { return version_; }

 private:
  template <typename>
  friend class BasicAccessor;

  static constexpr std::uint32_t kNoBlock = 0;  // block 0 holds the root word, so it is never free

  /** Makes room for n more blocks, or throws before anything changes. */
  void reserveBlocks(std::size_t n);
  /** Moves the live blocks into the free blocks below them, so that the pool ends at its last live block. */
  void compactPool();
  std::uint32_t allocBlock();
  void freeBlock(std::uint32_t block);

  /**
   * Grows the root until it covers the aligned cube of 2^level cells per axis at (x, y, z), in tree
   * coordinates (level 0: one cell), and reserves the blocks that writing the cube then takes.
   */
  void growToCover(std::uint32_t x, std::uint32_t y, std::uint32_t z, unsigned level);
  /**
   * Expands the bitmap word at path[level] down to level 1 along (x, y, z), filling path[level-1..1].
   * Each new block holds the expanded octant states, so the cells keep their values.
   */
  void expandTo(std::size_t* path, unsigned level, std::uint32_t x, std::uint32_t y, std::uint32_t z);
  /**
   * Replaces the leaf word at path[1] by `updated`, keeps the counts, and folds it upwards if it became
   * uniform. Returns the level of the bitmap word now holding the leaf's cells.
   */
  unsigned writeLeaf(const std::size_t* path, NodeWord updated);
  /**
   * The leaf at path[1] (a level-1 word) with cells `mask` updated by OctoMap's rule, cell o by update[o].
   * Returns the level now holding the leaf's cells, as writeLeaf.
   */
  unsigned updateLeaf(const std::size_t* path, std::uint32_t mask, const float* update);
  /** Writes cells `mask` of the leaf at path[1] to `state`, settled. */
  unsigned setLeafStates(const std::size_t* path, std::uint32_t mask, CellState state);
  /** Sets cell o of the leaf at path[1] to `value`. */
  unsigned setLeafValue(const std::size_t* path, unsigned o, float value);
  /** Writes a leaf's 8 values (NaN: unknown) as its word and, if a cell is unsettled, its values. */
  unsigned commitLeaf(const std::size_t* path, const float (&v)[8]);
  void leafValues(std::size_t at, float (&v)[8]) const;
  /** The pool as LeafValues needs it for the memory cap. */
  LeafValues::Pool pool() const { return {words_.size(), words_.capacity(), max_bytes_}; }
  /** Gives the flagged words, in pre-order, the values of `values` (a canonical pool's). */
  void installValues(std::vector<float> values);
  /** toMaxLikelihood below the word at pool offset `at`; returns the word, folded where it became uniform. */
  NodeWord settleSubtree(std::size_t at);
  /**
   * The word at path[level] became uniform or a cube of one value: folds blocks upward (foldedBlock).
   * Returns the new bottom level.
   */
  unsigned collapseFrom(const std::size_t* path, unsigned level);
  /** Writes the aligned cube of 2^level cells per axis whose corner is c. */
  void setCube(const TreeCoord& c, unsigned level, CellState state);
  /** setCube with a log-odds; a cube between the clamps the palette cannot name is written cell by cell. */
  void setCubeLogOdds(const TreeCoord& c, unsigned level, float log_odds);
  /**
   * Makes the cube at c, of level >= 1, the word `cube`: uniform, or a cube of one value (a flagged word
   * whose octants all hold it).
   */
  void writeCube(const TreeCoord& c, unsigned level, NodeWord cube);
  /**
   * Replaces the bitmap word at pool offset `at`, above level 1, by a new block of its octants as words
   * (node::octantWord); room for the block must be reserved. Returns the block's first offset.
   */
  std::size_t splitWord(std::size_t at);
  /** The word the block at pool offset `first` folds into: all uniform, or cubes of one value and
   * unknown ones; 0 when it does not fold. */
  NodeWord foldedBlock(std::size_t first) const;
  /**
   * Folds the block at pool offset `first` into its parent's word at `parent_at`, if it folds
   * (foldedBlock): keeps the counts and frees the block. Returns the parent's new word, or 0.
   */
  NodeWord foldBlock(std::size_t parent_at, std::size_t first);
  /** Folds, below the word at pool offset `at`, every block that folds (a pool read from a file). */
  void foldSubtree(std::size_t at);

  /** Frees the blocks below the word at pool offset `at`, of level `level`, and takes its cells out of the
   * counts. */
  void releaseSubtree(std::size_t at, unsigned level);
  /** Adds `update` to every cell of the aligned cube at c, whole uniform cubes at once where it can. */
  void updateCube(const TreeCoord& c, unsigned level, float update);

  /** Visits the cells of a cube in Morton order, the order a fully expanded tree would give. */
  template <typename Visitor>
  static void visitCube(const TreeCoord& corner, unsigned level, Visitor& visit);
  /** Visits the maximal uniform known cubes below the node, skipping subtrees `overlaps` rejects. */
  template <typename Overlaps, typename Visitor>
  bool walkRegions(const NodeView& n, Overlaps& overlaps, Visitor& visit) const;
  /** forEachLogOdds below the word at pool offset `at`, of the given level and corner. */
  template <typename Visitor>
  bool walkLogOdds(std::size_t at, unsigned level, const TreeCoord& corner, Visitor& visit) const;

  CellGrid grid_;
  std::vector<NodeWord> words_;  // block b is words_[8b .. 8b+7]; words_[0] is the root
  unsigned root_level_ = 1;
  TreeCoord base_;
  std::uint32_t free_head_ = kNoBlock;
  std::size_t free_blocks_ = 0;
  std::size_t live_blocks_ = 0;
  std::size_t max_bytes_ = std::numeric_limits<std::size_t>::max();
  std::uint64_t version_ = 0;
  std::array<std::uint64_t, 3> counts_{};  // indexed by CellState; the Unknown entry is unused
  SensorModel model_;
  UpdateRule rule_ = UpdateRule::Binary;
  LeafValues values_;             // the flagged leaves' log-odds
  std::size_t value_leaves_ = 0;  // flagged words
};

inline unsigned FastOctTree::writeLeaf(const std::size_t* path, NodeWord updated) {
  NodeWord& leaf = words_[path[1]];
  for (CellState s : {CellState::Free, CellState::Occupied}) {
    counts_[std::size_t(s)] += node::popcount(node::octantMask(updated, s));
    counts_[std::size_t(s)] -= node::popcount(node::octantMask(leaf, s));
  }
  value_leaves_ += std::size_t(node::hasValues(updated)) - std::size_t(node::hasValues(leaf));
  leaf = updated;
  return node::isUniform(updated) || node::isValueUniform(updated) ? collapseFrom(path, 1) : 1;
}

template <typename Overlaps, typename Visitor>
bool FastOctTree::walkRegions(const NodeView& n, Overlaps& overlaps, Visitor& visit) const {
  const Key corner = n.corner.key();
  if (!overlaps(corner, n.level)) return true;
  if (n.isUniform() || node::isValueUniform(n.word)) {  // a cube of one state
    if (n.uniformState() == CellState::Unknown) return true;
    const Region region{corner, n.level, n.uniformState()};
    if constexpr (std::is_same<decltype(visit(region)), bool>::value) {
      return visit(region);
    } else {
      visit(region);
      return true;
    }
  }
  for (unsigned o = 0; o < 8; ++o)
    if (!walkRegions(n.child(words_.data(), o), overlaps, visit)) return false;
  return true;
}

template <typename Visitor>
void FastOctTree::forEachRegion(Visitor&& visit) const {
  auto everywhere = [](const Key&, unsigned) { return true; };
  walkRegions(root(), everywhere, visit);
}

template <typename Visitor>
void FastOctTree::forEachRegionInBox(const Key& lo, const Key& hi, Visitor&& visit) const {
  auto overlaps = [&](const Key& c, unsigned level) {
    const std::int64_t side = std::int64_t(1) << level;
    return c.x <= hi.x && c.x + side > lo.x && c.y <= hi.y && c.y + side > lo.y && c.z <= hi.z &&
           c.z + side > lo.z;
  };
  walkRegions(root(), overlaps, visit);
}

template <typename Visitor>
void FastOctTree::forEachRegionOutsideBox(const Key& lo, const Key& hi, Visitor&& visit) const {
  auto reaches_out = [&](const Key& c, unsigned level) {
    const std::int64_t last = (std::int64_t(1) << level) - 1;
    return c.x < lo.x || c.x + last > hi.x || c.y < lo.y || c.y + last > hi.y || c.z < lo.z ||
           c.z + last > hi.z;
  };
  walkRegions(root(), reaches_out, visit);
}

template <typename Visitor>
void FastOctTree::forEachLogOdds(Visitor&& visit) const {
  walkLogOdds(0, root_level_, base_, visit);
}

template <typename Visitor>
bool FastOctTree::walkLogOdds(std::size_t at, unsigned level, const TreeCoord& corner, Visitor& visit) const {
  const auto call = [&](const Region& region, float log_odds) {
    if constexpr (std::is_same<decltype(visit(region, log_odds)), bool>::value) {
      return visit(region, log_odds);
    } else {
      visit(region, log_odds);
      return true;
    }
  };
  const NodeWord w = words_[at];
  if (node::isUniform(w) || node::isValueUniform(w)) {
    const CellState s = node::uniformState(w);
    return s == CellState::Unknown || call(Region{corner.key(), level, s}, leafValue(at, 0));
  }
  for (unsigned o = 0; o < 8; ++o) {
    const TreeCoord c = corner.child(o, level - 1);
    if (!node::isBitmap(w)) {
      if (!walkLogOdds(node::childOffset(w, o), level - 1, c, visit)) return false;
      continue;
    }
    const CellState s = node::state(w, o);  // an octant of a bitmap is uniform; a leaf's may hold a float
    if (s != CellState::Unknown && !call(Region{c.key(), level - 1, s}, leafValue(at, o))) return false;
  }
  return true;
}

template <typename Visitor>
void FastOctTree::forEachCell(CellState state, Visitor&& visit) const {
  if (state == CellState::Unknown)
    throw std::invalid_argument("pcl::fot::FastOctTree::forEachCell: unknown cells are not enumerable");
  forEachRegion([&](const Region& r) {
    if (r.state == state) visitCube(TreeCoord(r.min_key), r.level, visit);
  });
}

template <typename Visitor>
void FastOctTree::visitCube(const TreeCoord& corner, unsigned level, Visitor& visit) {
  if (level == 0) {
    visit(corner.key());
    return;
  }
  for (unsigned o = 0; o < 8; ++o) visitCube(corner.child(o, level - 1), level - 1, visit);
}

}  // namespace fot
}  // namespace pcl
