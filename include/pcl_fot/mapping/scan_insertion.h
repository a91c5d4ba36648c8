#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <pcl_fot/dense/fast_occ_mesh.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {

/** A box of cells, bounds included. */
struct KeyBox {
  Key min, max;
  bool contains(const Key& k) const {
    return k.x >= min.x && k.x <= max.x && k.y >= min.y && k.y <= max.y && k.z >= min.z && k.z <= max.z;
  }
};

struct ScanOptions {
  /** Rays longer than this mark free space up to it and no endpoint. Zero or less: no limit. */
  double max_range = -1.0;
  /** Points closer to the sensor than this are ignored altogether. */
  double min_range = 0.0;
  /** Tree writes go through LineBurstAccess; switch it off only to measure what it is worth. */
  bool line_burst = true;
  /** The rule for this scan; unset, the map's (FastOctTree::getUpdateRule). The grid knows only Binary. */
  std::optional<UpdateRule> rule;
  /**
   * OctoMap's discretize: points sharing a cell count once, and their rays run to the cell's centre. Fewer
   * rays, slightly different free cells.
   */
  bool discretize = false;
  /**
   * Threads that walk the rays into the tree; 0 takes every hardware thread. Each walks a share of the rays
   * and gathers its cells, the shares are joined and the tree written once: the map is the same, word for
   * word, for any count. A binary scan on one thread writes as it walks instead. The grid walks on one.
   */
  unsigned threads = 0;
  /**
   * Only the cells inside this box are written (a tile of a tiled map). The rays are walked as without it,
   * from the sensor, so each cell inside gets exactly the update a whole-map insertion gives it; rays that
   * cannot reach the box are not walked. The grid takes no region.
   */
  std::optional<KeyBox> region;
};

struct ScanStats {
  std::size_t rays = 0;            ///< points traced, truncated ones included
  std::size_t occupied = 0;        ///< endpoints marked occupied
  std::size_t truncated = 0;       ///< rays cut at max_range: free space only
  std::size_t too_close = 0;       ///< points within min_range, ignored
  std::size_t non_finite = 0;      ///< NaN or Inf points, skipped
  std::size_t out_of_range = 0;    ///< points beyond the key range, skipped
  std::size_t outside_region = 0;  ///< rays that cannot reach ScanOptions::region, not walked
  std::size_t merged = 0;          ///< points whose cell an earlier point of the scan had (discretize only)
  std::uint64_t ray_cells = 0;  ///< cells the rays pass, each a Free write for the grid; endpoints excluded
  /**
   * Distinct cells marked free (passed, no endpoint): ray_cells counts each once per ray. Counted where the
   * cells are gathered before the tree is written (the log-odds rule, more than one thread, or rays in
   * bundles, see skipped_cells); 0 elsewhere.
   */
  std::uint64_t free_cells = 0;
  /**
   * Of ray_cells, those passed without a step: on dense scans, the stretches near the sensor that bundles
   * of rays certainly pass are marked once for all, and each ray is walked from where its bundle stopped.
   */
  std::uint64_t skipped_cells = 0;
};

/**
 * Inserts one scan with ray tracing. `xyz` holds `count` points in the map frame, point i's x, y, z at
 * byte offset i * stride_bytes; `sensor` is the sensor's position in the map frame.
 *
 * The cells are OctoMap's insertPointCloud's: every cell a ray passes (see traceSegment), and every
 * endpoint's cell; within one scan an endpoint's cell counts as an endpoint only. With the Binary rule, the
 * paper's, the passed cells become free and the endpoints occupied, whatever they held: the latest scan
 * wins. With the LogOdds rule each passed cell gets one miss and each endpoint one hit, however many rays
 * reach it, as OctoMap's updateNode adds them (SensorModel): after the same scans every cell holds
 * OctoMap's float. The grid knows the binary rule only, and skips cells outside its cube.
 *
 * The calling thread keeps the buffers a scan takes, in proportion to its points, for its next scan (into
 * any map): a sequence of scans allocates them once. A scan of far fewer points than the largest one so far
 * lets them go; traceScan shares them.
 *
 * Throws std::invalid_argument for a non-finite sensor position, the LogOdds rule or a region on the grid,
 * and std::out_of_range for a sensor beyond the key range; bad points are skipped and counted.
 */
ScanStats insertRays(FastOctTree& map, const float sensor[3], const float* xyz, std::size_t count,
                     std::size_t stride_bytes, const ScanOptions& options = {});

/**
 * The cells one scan updates, a 4×4×4 block at a time: the block (tree coordinates / 4, see tree_coord.h)
 * and, as bits x + 4y + 16z of its cells, those a ray passes and the endpoints.
 */
struct ScanBlock {
  std::uint32_t at[3];
  std::uint64_t passed = 0;
  std::uint64_t hit = 0;  ///< endpoints: a hit and no miss
};

/**
 * Walks a scan's rays as insertRays does and returns its cells, each once, without writing a map: a scan
 * traced once can be written into several maps, or a region at a time (tiled mapping). `map` gives the
 * grid; the options' rule does not matter here. Throws as insertRays.
 */
std::vector<ScanBlock> traceScan(const FastOctTree& map, const float sensor[3], const float* xyz,
                                 std::size_t count, std::size_t stride_bytes, const ScanOptions& options = {},
                                 ScanStats* stats = nullptr);
/**
 * Writes a traced scan into `map`, as insertRays writes it, with the options' rule and region (the ranges
 * and threads were the trace's). The blocks must come from traceScan on a map of the same grid; returns
 * the cells marked free.
 */
std::uint64_t applyScan(FastOctTree& map, const ScanBlock* blocks, std::size_t count,
                        const ScanOptions& options = {});
ScanStats insertRays(FastOccMesh& map, const float sensor[3], const float* xyz, std::size_t count,
                     std::size_t stride_bytes, const ScanOptions& options = {});

}  // namespace fot
}  // namespace pcl
