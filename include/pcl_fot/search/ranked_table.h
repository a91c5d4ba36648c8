#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <pcl_fot/search/point_boxes.h>
#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace detail {

/**
 * The static half of a PointIndex: each occupied cell's points in one run of a table, the runs in the
 * tree's Morton order, so that a cell's rank finds its run; one more run after the cells' holds the
 * outliers (finite points beyond the key range). Each run has the box of its points and each node word the
 * box of the points under it; a crowded run is split into boxes of its points (PointBox).
 */
class RankedTable {
 public:
  using Box = std::array<float, 6>;  // low x, y, z, high x, y, z

  /**
   * Lists the points of `tree`'s occupied cells: point ids[j] (its x, y, z at xyz + ids[j] * stride_bytes)
   * lies in cell keys[j]; the ids after the keys' are the outliers.
   */
  void build(const FastOctTree& tree, const std::vector<Key>& keys, const std::vector<std::int32_t>& ids,
             const float* xyz, std::size_t stride_bytes);

  std::size_t size() const { return index_.size(); }
  /** The rank of the occupied cell `k` in the Morton order of `tree`, the tree built on; `reader` reads it.
   */
  std::uint32_t cellRank(const FastOctTree& tree, ConstAccessor& reader, const Key& k) const;
  /** Per pool word: the rank of the first occupied cell under a bitmap word (NeighbourWalk's ranks). */
  const std::uint64_t* ranks() const { return ranks_.data(); }
  /** The run of the outliers, after the cells'. */
  std::uint64_t outlierRun() const { return start_.size() - 2; }
  /** Run r's points are the table's slots [begin(r), end(r)). */
  std::uint32_t begin(std::uint64_t r) const { return start_[r]; }
  std::uint32_t end(std::uint64_t r) const { return start_[r + 1]; }
  /** The points' x, y, z, by slot. */
  const float* points() const { return xyz_.data(); }
  std::int32_t index(std::uint32_t slot) const { return index_[slot]; }
  const Box& runBox(std::uint64_t r) const { return run_box_[r]; }
  const Box& wordBox(std::size_t word) const { return word_box_[word]; }
  /** A crowded run's boxes, and the first of run r's. */
  const PointBox* crowd() const { return crowd_.data(); }
  std::uint32_t crowdRoot(std::uint64_t r) const;

  /** Calls visit(cell, begin, end) for each occupied cell of `tree` and its slots, in Morton order. */
  template <typename Visit>
  void forEachRun(const FastOctTree& tree, Visit&& visit) const {
    ConstAccessor reader(tree);
    tree.forEachCell(CellState::Occupied, [&](const Key& cell) {
      const std::uint32_t r = cellRank(tree, reader, cell);
      visit(cell, start_[r], start_[r + 1]);
    });
  }
  std::size_t memoryBytes() const;

 private:
  /** Lists each cell's points contiguously, by rank, the outliers last. */
  void fillTable(const FastOctTree& tree, const std::vector<Key>& keys, const std::vector<std::int32_t>& ids,
                 const float* xyz, std::size_t stride_bytes, std::uint64_t cells);
  /** The bounding box of each run's points (run_box_). */
  void boxRuns(std::uint64_t cells);
  /** Splits the runs of more than kCrowded points into boxes (crowd_). */
  void splitCrowdedRuns(std::uint64_t cells);

  std::vector<std::uint64_t> ranks_;
  std::vector<std::uint32_t> start_;  // run -> its first slot; one more entry ends the last run
  std::vector<float> xyz_;            // the points, by slot
  std::vector<std::int32_t> index_;   // their indices as given
  std::vector<Box> run_box_;          // by run
  std::vector<Box> word_box_;         // by pool word
  // Crowded runs' boxes (slots), in pre-order: crowd_root_ holds each one's run and first box, by run.
  std::vector<PointBox> crowd_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> crowd_root_;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
