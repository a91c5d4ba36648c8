#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <pcl_fot/detail/bits.h>
#include <pcl_fot/tree/fast_oct_tree.h>
#include <pcl_fot/tree/key.h>

namespace pcl {
namespace fot {

/**
 * FastOccMesh, the paper's baseline (§III): a dense cube of side × side × side cells with one occupancy bit
 * per cell in one flat array, 1024³ cells = 128 MiB by default.
 *
 * It offers the FastOctTree's cell interface. Free cells need a second bit: the first Free write
 * interleaves a free word after every occupancy word, so one cell's two bits share a cache line, and
 * the grid then holds 2 bits per cell. A binary map (nothing marked free) stays at 1 bit per cell.
 * Cells outside the cube read as Unknown; writing them is an error.
 */
class FastOccMesh {
 public:
  using Ptr = std::shared_ptr<FastOccMesh>;
  using ConstPtr = std::shared_ptr<const FastOccMesh>;

  static constexpr std::uint32_t kDefaultSide = 1024;

  /** A cube of `side` cells per axis whose lowest cell is min_key; by default centred on key 0. */
  explicit FastOccMesh(const CellGrid& grid, std::uint32_t side = kDefaultSide);
  FastOccMesh(const CellGrid& grid, std::uint32_t side, const Key& min_key);

  const CellGrid& getGrid() const { return grid_; }
  double getResolution() const { return grid_.resolution(); }
  std::uint32_t getSide() const { return side_; }
  const Key& getMinKey() const { return min_key_; }
  bool contains(const Key& key) const {
    return std::uint32_t(key.x - min_key_.x) < side_ && std::uint32_t(key.y - min_key_.y) < side_ &&
           std::uint32_t(key.z - min_key_.z) < side_;
  }

  CellState getCell(const Key& key) const {
    if (!contains(key)) return CellState::Unknown;
    const std::uint64_t i = index(key);
    const std::size_t w = wordOf(i);
    const std::uint64_t bit = std::uint64_t(1) << (i & 63);
    if (words_[w] & bit) return CellState::Occupied;
    return (has_free_ && (words_[w + 1] & bit)) ? CellState::Free : CellState::Unknown;
  }

  /** Throws std::out_of_range for a key outside the cube. */
  void setCell(const Key& key, CellState state) {
    if (!contains(key)) throwOutside(key);
    if (state == CellState::Free && !has_free_) addFreePlane();
    const std::uint64_t i = index(key);
    const std::size_t w = wordOf(i);
    const std::uint64_t bit = std::uint64_t(1) << (i & 63);
    std::uint64_t& occ = words_[w];
    const bool was_occ = (occ & bit) != 0;
    const bool was_free = has_free_ && (words_[w + 1] & bit);
    const CellState old = was_occ ? CellState::Occupied : (was_free ? CellState::Free : CellState::Unknown);
    if (old == state) return;
    occ = state == CellState::Occupied ? (occ | bit) : (occ & ~bit);
    if (has_free_) {
      std::uint64_t& fr = words_[w + 1];
      fr = state == CellState::Free ? (fr | bit) : (fr & ~bit);
    }
    --counts_[std::size_t(old)];
    ++counts_[std::size_t(state)];
  }
  void eraseCell(const Key& key) {
    if (contains(key)) setCell(key, CellState::Unknown);
  }

  CellState getCellAtPoint(double x, double y, double z) const;
  void setCellAtPoint(double x, double y, double z, CellState state);
  void eraseCellAtPoint(double x, double y, double z) { setCellAtPoint(x, y, z, CellState::Unknown); }

  /** As FastOctTree::insertKeys; keys outside the cube count as out of range. */
  InsertStats insertKeys(const Key* keys, std::size_t count, CellState state = CellState::Occupied);
  /** As FastOctTree::insertPoints; points outside the cube count as out of range. */
  InsertStats insertPoints(const float* xyz, std::size_t count, std::size_t stride_bytes,
                           CellState state = CellState::Occupied);

  /** Visits every cell holding `state` (other than Unknown), x fastest, then y, then z. */
  template <typename Visitor>
  void forEachCell(CellState state, Visitor&& visit) const;

  std::uint64_t getOccupiedCount() const { return counts_[std::size_t(CellState::Occupied)]; }
  std::uint64_t getFreeCount() const { return counts_[std::size_t(CellState::Free)]; }
  bool hasFreePlane() const { return has_free_; }
  std::size_t getMemoryBytes() const { return sizeof(*this) + words_.capacity() * sizeof(std::uint64_t); }

  /** Sets every cell to Unknown, in place; the memory layout stays as it is. */
  void clear();

 private:
  std::uint64_t index(const Key& key) const {
    return std::uint64_t(std::uint32_t(key.x - min_key_.x)) +
           side_ * (std::uint64_t(std::uint32_t(key.y - min_key_.y)) +
                    side_ * std::uint64_t(std::uint32_t(key.z - min_key_.z)));
  }
  std::size_t wordOf(std::uint64_t i) const { return std::size_t(i >> 6) << (has_free_ ? 1 : 0); }
  [[noreturn]] void throwOutside(const Key& key) const;
  void addFreePlane();

  CellGrid grid_;
  std::uint32_t side_;
  Key min_key_;
  bool has_free_ = false;
  std::vector<std::uint64_t> words_;
  std::array<std::uint64_t, 3> counts_{};
};

template <typename Visitor>
void FastOccMesh::forEachCell(CellState state, Visitor&& visit) const {
  const std::uint64_t cells = std::uint64_t(side_) * side_ * side_;
  const std::size_t stride = has_free_ ? 2 : 1;
  for (std::uint64_t first = 0; first < cells; first += 64) {
    const std::size_t w = std::size_t(first >> 6) * stride;
    std::uint64_t bits = state == CellState::Occupied              ? words_[w]
                         : (state == CellState::Free && has_free_) ? words_[w + 1]
                                                                   : 0;
    while (bits) {
      const std::uint64_t i = first + detail::lowestBit(bits);
      bits &= bits - 1;
      const std::uint64_t plane = std::uint64_t(side_) * side_;
      visit(Key{min_key_.x + std::int32_t(i % side_), min_key_.y + std::int32_t((i / side_) % side_),
                min_key_.z + std::int32_t(i / plane)});
    }
  }
}

}  // namespace fot
}  // namespace pcl
