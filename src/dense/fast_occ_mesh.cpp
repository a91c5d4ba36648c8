#include <pcl_fot/dense/fast_occ_mesh.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace pcl {
namespace fot {

namespace {
Key centredMinKey(std::uint32_t side) {
  const std::int32_t half = std::int32_t(side / 2);
  return Key{-half, -half, -half};
}
}  // namespace

FastOccMesh::FastOccMesh(const CellGrid& grid, std::uint32_t side)
    : FastOccMesh(grid, side, centredMinKey(side)) {}

FastOccMesh::FastOccMesh(const CellGrid& grid, std::uint32_t side, const Key& min_key)
    : grid_(grid), side_(side), min_key_(min_key) {
  if (side == 0) throw std::invalid_argument("pcl::fot::FastOccMesh: the side must be at least one cell");
  const auto fits = [side](std::int32_t lo) {
    return lo >= kMinKey && std::int64_t(lo) + side - 1 <= kMaxKey;
  };
  if (!fits(min_key.x) || !fits(min_key.y) || !fits(min_key.z))
    throw std::out_of_range("pcl::fot::FastOccMesh: the cube from " + toString(min_key) + " with side " +
                            std::to_string(side) + " leaves the supported key range");
  const std::uint64_t cells = std::uint64_t(side) * side * side;
  words_.assign(std::size_t((cells + 63) / 64), 0);
}

void FastOccMesh::throwOutside(const Key& key) const {
  throw std::out_of_range("pcl::fot::FastOccMesh::setCell: key " + toString(key) +
                          " is outside the grid from " + toString(min_key_) + " with side " +
                          std::to_string(side_));
}

void FastOccMesh::addFreePlane() {
  std::vector<std::uint64_t> interleaved(words_.size() * 2, 0);
  for (std::size_t i = 0; i < words_.size(); ++i) interleaved[2 * i] = words_[i];
  words_.swap(interleaved);
  has_free_ = true;
}

CellState FastOccMesh::getCellAtPoint(double x, double y, double z) const {
  Key key;
  return grid_.finitePointToKey(x, y, z, key, "pcl::fot::FastOccMesh::getCellAtPoint") ? getCell(key)
                                                                                       : CellState::Unknown;
}

void FastOccMesh::setCellAtPoint(double x, double y, double z, CellState state) {
  Key key;
  if (!grid_.finitePointToKey(x, y, z, key, "pcl::fot::FastOccMesh::setCellAtPoint") || !contains(key))
    throw std::out_of_range("pcl::fot::FastOccMesh::setCellAtPoint: the point lies outside the grid");
  setCell(key, state);
}

InsertStats FastOccMesh::insertKeys(const Key* keys, std::size_t count, CellState state) {
  InsertStats stats;
  for (std::size_t i = 0; i < count; ++i) {
    if (!contains(keys[i])) {
      ++stats.out_of_range;
      continue;
    }
    setCell(keys[i], state);
    ++stats.inserted;
  }
  return stats;
}

InsertStats FastOccMesh::insertPoints(const float* xyz, std::size_t count, std::size_t stride_bytes,
                                      CellState state) {
  InsertStats stats;
  const char* bytes = reinterpret_cast<const char*>(xyz);
  for (std::size_t i = 0; i < count; ++i) {
    const float* p = reinterpret_cast<const float*>(bytes + i * stride_bytes);
    Key key;
    if (grid_.pointToKey(p[0], p[1], p[2], key) && contains(key)) {
      setCell(key, state);
      ++stats.inserted;
    } else if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) {
      ++stats.out_of_range;
    } else {
      ++stats.non_finite;
    }
  }
  return stats;
}

void FastOccMesh::clear() {
  std::fill(words_.begin(), words_.end(), 0);  // in place: the pages stay mapped
  counts_ = {0, 0, 0};
}

}  // namespace fot
}  // namespace pcl
