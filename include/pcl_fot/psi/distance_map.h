#pragma once

#include <cstdint>
#include <vector>

#include <pcl_fot/dense/fast_occ_mesh.h>
#include <pcl_fot/psi/psi.h>

namespace pcl {
namespace fot {

/**
 * dmap_v, the paper's baseline for ψ (§IV): for every cell of a FastOccMesh's cube, the exact Manhattan
 * distance, in cells, to the nearest cell holding `value`. Computed by the two-pass city-block distance
 * transform (a forward raster pass with the x-1, y-1, z-1 neighbours, then a backward one with x+1, y+1,
 * z+1), which is linear in the number of cells and exact for this metric. Shortest Manhattan paths between
 * two cells of the cube stay inside it, so the cube alone gives exact distances for its cells.
 * Two bytes per cell: 2 GiB for the paper's 1024³ grid.
 */
class DistanceMap {
 public:
  /** Where the cube holds no cell of the value. */
  static constexpr std::uint16_t kNone = 0xFFFF;

  /** An empty map, to be filled by compute(). */
  DistanceMap() = default;
  /** Throws std::invalid_argument for a cube whose distances would not fit 16 bits (side over 21845). */
  DistanceMap(const FastOccMesh& grid, CellState value) { compute(grid, value); }

  /**
   * Makes this the map of `grid` and `value`, reusing its storage for a cube of the same side: memory not
   * yet touched costs a page fault per 4 KB, which on a virtual machine can take longer than the transform
   * (doc/benchmarks.md gives both). Throws as the constructor does, leaving the map as it was.
   */
  void compute(const FastOccMesh& grid, CellState value);

  /** The distance of a cell of the cube; kNone if the cube holds no cell of the value. */
  std::uint16_t at(const Key& key) const { return distances_[index(key)]; }
  bool empty() const { return empty_; }

 private:
  std::size_t index(const Key& k) const {
    return std::size_t(k.x - min_key_.x) +
           side_ * (std::size_t(k.y - min_key_.y) + side_ * std::size_t(k.z - min_key_.z));
  }

  std::size_t side_ = 0;
  Key min_key_;
  bool empty_ = true;
  std::vector<std::uint16_t> distances_;
};

/**
 * ψ(a, b) the dmap_v way: a distance map for each map and value, read off at the other map's cells. The
 * same definition and result as psi() on trees. Throws std::invalid_argument unless both grids have the
 * same resolution, origin and cube.
 */
PsiResult psiByDistanceMaps(const FastOccMesh& a, const FastOccMesh& b, const PsiOptions& options = {});
/** psiByDistanceMaps computing its maps, one after another, in `workspace`, which keeps the storage for the
 * next call. */
PsiResult psiByDistanceMaps(const FastOccMesh& a, const FastOccMesh& b, DistanceMap& workspace,
                            const PsiOptions& options = {});

}  // namespace fot
}  // namespace pcl
