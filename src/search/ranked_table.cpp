#include <pcl_fot/search/ranked_table.h>

#include <algorithm>
#include <limits>

#include <pcl_fot/detail/bits.h>

namespace pcl {
namespace fot {
namespace detail {
namespace {

using Box = RankedTable::Box;
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr Box kNoBox = {kInf, kInf, kInf, -kInf, -kInf, -kInf};

void unite(Box& box, const Box& other) {
  for (int a = 0; a < 3; ++a)
    box[a] = std::min(box[a], other[a]), box[3 + a] = std::max(box[3 + a], other[3 + a]);
}

/** Numbers the occupied cells in Morton order: each bitmap word gets the rank of its first one. */
std::uint64_t assignRanks(const FastOctTree& tree, const NodeView& n, std::size_t offset, std::uint64_t next,
                          std::vector<std::uint64_t>& ranks) {
  if (n.isBitmap()) {
    ranks[offset] = next;
    return next + node::cellsIn(node::popcount(node::octantMask(n.word, CellState::Occupied)), n.level - 1);
  }
  for (unsigned o = 0; o < 8; ++o)
    next = assignRanks(tree, n.child(tree.words(), o), n.childOffset(o), next, ranks);
  return next;
}

/** The box of the points under each node word, from their runs' boxes (by rank): words[offset]. */
Box boxWords(const FastOctTree& tree, const NodeView& n, std::size_t offset,
             const std::vector<std::uint64_t>& ranks, const std::vector<Box>& runs, std::vector<Box>& words) {
  Box box = kNoBox;
  if (n.isBitmap()) {
    const std::uint64_t first = ranks[offset],
                        count = node::cellsIn(node::popcount(node::octantMask(n.word, CellState::Occupied)),
                                              n.level - 1);
    for (std::uint64_t r = first; r < first + count; ++r) unite(box, runs[r]);
  } else {
    for (unsigned o = 0; o < 8; ++o)
      unite(box, boxWords(tree, n.child(tree.words(), o), n.childOffset(o), ranks, runs, words));
  }
  words[offset] = box;
  return box;
}

}  // namespace

void RankedTable::build(const FastOctTree& tree, const std::vector<Key>& keys,
                        const std::vector<std::int32_t>& ids, const float* xyz, std::size_t stride_bytes) {
  ranks_.assign(tree.poolWords(), 0);
  const std::uint64_t cells = assignRanks(tree, tree.root(), 0, 0, ranks_);
  fillTable(tree, keys, ids, xyz, stride_bytes, cells);
  boxRuns(cells);
  word_box_.assign(tree.poolWords(), kNoBox);
  boxWords(tree, tree.root(), 0, ranks_, run_box_, word_box_);
  splitCrowdedRuns(cells);
}

std::uint32_t RankedTable::cellRank(const FastOctTree& tree, ConstAccessor& reader, const Key& k) const {
  const unsigned level = reader.locatePath(k);
  const std::size_t offset = reader.pathOffset(level);
  const TreeCoord u(k);
  const unsigned o = u.octant(level);
  const std::uint32_t before = node::octantMask(tree.words()[offset], CellState::Occupied) & ((1u << o) - 1u);
  const std::uint32_t inner = tree_coord::lowMask(level - 1);
  return std::uint32_t(ranks_[offset] + node::cellsIn(node::popcount(before), level - 1) +
                       morton3(u[0] & inner, u[1] & inner, u[2] & inner));
}

std::uint32_t RankedTable::crowdRoot(std::uint64_t r) const {
  return std::lower_bound(crowd_root_.begin(), crowd_root_.end(), std::make_pair(std::uint32_t(r), 0u))
      ->second;
}

void RankedTable::fillTable(const FastOctTree& tree, const std::vector<Key>& keys,
                            const std::vector<std::int32_t>& ids, const float* xyz, std::size_t stride_bytes,
                            std::uint64_t cells) {
  // Each point's cell rank, then a counting sort into the table. The outliers come last, as one more run.
  std::vector<std::uint32_t> rank_of(ids.size(), std::uint32_t(cells));
  ConstAccessor reader(tree);
  for (std::size_t j = 0; j < keys.size(); ++j) rank_of[j] = cellRank(tree, reader, keys[j]);
  start_.assign(std::size_t(cells) + 2, 0);
  for (std::uint32_t r : rank_of) ++start_[r + 1];
  for (std::size_t c = 0; c <= cells; ++c) start_[c + 1] += start_[c];
  xyz_.resize(3 * ids.size());
  index_.resize(ids.size());
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  const char* bytes = reinterpret_cast<const char*>(xyz);
  for (std::size_t j = 0; j < ids.size(); ++j) {
    const std::uint32_t at = fill[rank_of[j]]++;
    const float* p = reinterpret_cast<const float*>(bytes + std::size_t(ids[j]) * stride_bytes);
    std::copy(p, p + 3, &xyz_[3 * std::size_t(at)]);
    index_[at] = ids[j];
  }
}

void RankedTable::boxRuns(std::uint64_t cells) {
  run_box_.resize(std::size_t(cells) + 1);
  for (std::size_t c = 0; c <= cells; ++c) {
    Box& box = run_box_[c];
    box = kNoBox;
    for (std::uint32_t i = start_[c]; i < start_[c + 1]; ++i)
      for (int a = 0; a < 3; ++a) {
        box[a] = std::min(box[a], xyz_[3 * std::size_t(i) + a]);
        box[3 + a] = std::max(box[3 + a], xyz_[3 * std::size_t(i) + a]);
      }
  }
}

void RankedTable::splitCrowdedRuns(std::uint64_t cells) {
  crowd_.clear();
  crowd_root_.clear();
  std::vector<BucketPoint> run;
  for (std::size_t c = 0; c <= cells; ++c) {
    const std::uint32_t begin = start_[c], end = start_[c + 1];
    if (end - begin <= kCrowded) continue;
    run.resize(end - begin);
    for (std::uint32_t i = begin; i < end; ++i)
      run[i - begin] = {
          {xyz_[3 * std::size_t(i)], xyz_[3 * std::size_t(i) + 1], xyz_[3 * std::size_t(i) + 2]}, index_[i]};
    crowd_root_.emplace_back(std::uint32_t(c), std::uint32_t(crowd_.size()));
    splitIntoBoxes(run.data(), end - begin, begin, crowd_);
    for (std::uint32_t i = begin; i < end; ++i) {
      std::copy(run[i - begin].p, run[i - begin].p + 3, &xyz_[3 * std::size_t(i)]);
      index_[i] = run[i - begin].index;
    }
  }
}

std::size_t RankedTable::memoryBytes() const {
  return ranks_.capacity() * sizeof(std::uint64_t) + start_.capacity() * sizeof(std::uint32_t) +
         xyz_.capacity() * sizeof(float) + index_.capacity() * sizeof(std::int32_t) +
         (run_box_.capacity() + word_box_.capacity()) * sizeof(Box) + crowd_.capacity() * sizeof(PointBox) +
         crowd_root_.capacity() * sizeof(crowd_root_[0]);
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
