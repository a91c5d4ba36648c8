#pragma once
// Private to the library: the stretches of a scan's rays that the scan certainly passes, marked once.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <pcl_fot/mapping/scan_insertion.h>
#include <pcl_fot/tree/cell_grid.h>

namespace pcl {
namespace fot {
namespace detail {

/**
 * A dense scan's rays cross the cells near the sensor again and again: on a depth frame each cell walked is
 * walked 86 times. RayBundles finds, for bundles of rays with close directions, how far from the sensor
 * every cell their rays can pass is certainly passed by some ray of the scan, marks those cells once, and
 * tells each ray where its walk must begin. The walk from there (BlockRayWalker, with the cuts) and the
 * marked cells are together exactly the cells of the plain walk.
 *
 * Certainly passed: the directions are binned on the six faces of a cube around the sensor. A layer of
 * cells across a face's axis is swept outwards; a cell of it counts when some ray of that face crosses one
 * of three planes of the layer inside the cell by a margin and ends beyond the layer: OctoMap's walk,
 * rounding and all, then visits the cell (its error is a small fraction of the margin). Faces whose rays
 * are too sparse for that to pay are left to the walk. A bundle moves to the next layer
 * while every cell its rays can touch there counts and its rays end beyond; its rays' walks begin just
 * short of where it stopped.
 */
struct RayBundles {
  /** Per ray, the distance along it (as the walk measures it) from which it must be walked; 0: from the
   * sensor. Its cells before that are in `blocks`. Empty if the scan's rays are walked from the sensor. */
  std::vector<double> cuts;
  /** Cells passed, as ScanBlock's passed bits; a block may come more than once. */
  std::vector<ScanBlock> blocks;
};

/**
 * Bundles scans' rays. It keeps its buffers for the next scan, about 70 bytes a ray of the largest scan so
 * far (its face entry 40, its cut 8, its bundle's index 4, its share of the bins about 21): a sequence of
 * scans allocates them once, and threads write into memory that is already theirs.
 */
class RayBundler {
 public:
  RayBundler();
  ~RayBundler();
  RayBundler(const RayBundler&) = delete;
  RayBundler& operator=(const RayBundler&) = delete;

  /**
   * The bundles of the `count` rays from `sensor` to `ends` (xyz triples), as BlockRayWalker takes them,
   * swept on `workers` threads: the same cuts and cells for any count. Valid until the next call.
   */
  const RayBundles& bundle(const CellGrid& grid, const float sensor[3], const float* ends, std::size_t count,
                           std::size_t workers = 1);

  struct Buffers;  // the sweep's, in ray_bundles.cpp

 private:
  std::unique_ptr<Buffers> buffers_;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
