#pragma once

#include <cstddef>
#include <cstdint>

#include <pcl_fot/dense/fast_occ_mesh.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

struct ScanOptions {
  /** Rays longer than this mark free space up to it and no endpoint. Zero or less: no limit. */
  double max_range = -1.0;
  /** Points closer to the sensor than this are ignored altogether. */
  double min_range = 0.0;
  /** Tree writes go through LineBurstAccess; switch it off only to measure what it is worth. */
  bool line_burst = true;
};

struct ScanStats {
  std::size_t rays = 0;          ///< points traced, truncated ones included
  std::size_t occupied = 0;      ///< endpoints marked occupied
  std::size_t truncated = 0;     ///< rays cut at max_range: free space only
  std::size_t too_close = 0;     ///< points within min_range, ignored
  std::size_t non_finite = 0;    ///< NaN or Inf points, skipped
  std::size_t out_of_range = 0;  ///< points beyond the key range, skipped
  std::uint64_t ray_cells = 0;   ///< cells the rays pass, each a Free write for the grid; endpoints excluded
};

/**
 * Inserts one scan with ray tracing. `xyz` holds `count` points in the map frame, point i's x, y, z at
 * byte offset i * stride_bytes; `sensor` is the sensor's position in the map frame.
 *
 * The rules, the same for the tree and the grid: every cell a ray passes (see traceSegment) becomes free,
 * then every endpoint becomes occupied, so within one scan occupied wins over free. A cell that an earlier
 * scan marked occupied becomes free when a ray now passes through it. The grid skips cells outside its
 * cube. Throws std::invalid_argument for a non-finite sensor position and std::out_of_range for one beyond
 * the key range; bad points are skipped and counted.
 */
ScanStats insertRays(FastOctTree& map, const float sensor[3], const float* xyz, std::size_t count,
                     std::size_t stride_bytes, const ScanOptions& options = {});
ScanStats insertRays(FastOccMesh& map, const float sensor[3], const float* xyz, std::size_t count,
                     std::size_t stride_bytes, const ScanOptions& options = {});

}  // namespace fot
}  // namespace pcl
