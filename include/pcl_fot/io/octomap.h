#pragma once

#include <cstddef>
#include <string>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace io {

/**
 * OctoMap's files, read and written without the OctoMap library: the binary .bt format (maximum-likelihood
 * occupancy) and the full .ot format. OctoMap's grid has its cell boundaries on multiples of the resolution
 * and 65536 cells per axis centred on coordinate 0: key K = floor(c / res) + 32768. A map is representable
 * when its origin lies on that grid (a whole number of cells from 0 on each axis) and its known cells lie
 * within that cube; the free and occupied cells are then carried over exactly.
 */

struct OctoMapImportOptions {
  /**
   * Origin of the map to build; it must lie on OctoMap's grid (a whole number of cells from 0). At 0 the
   * map's nodes are OctoMap's and the import costs what the file holds; elsewhere a large cube may split
   * along its surface, within max_pool_bytes.
   */
  double origin[3] = {0.0, 0.0, 0.0};
  /** The map may not grow beyond this: a hostile file gets MemoryLimitError, not all the memory. */
  std::size_t max_pool_bytes = kDefaultMaxPoolBytes;
  /** The map's sensor model: its clamps say which of the file's values are settled. */
  SensorModel sensor_model;
};

/**
 * The .bt bytes of a tree: its maximum-likelihood map, pruned, as OctoMap's writeBinary writes it (a .bt
 * holds states only; reading one gives cells settled at the clamps). Throws std::invalid_argument, saying
 * why, if the map is not representable. The trees' nodes coincide when the map's origin is 0 (see
 * tree_coord): then the cost follows the tree. At another origin OctoMap's nodes are its nodes moved, and a
 * large cube may split along its surface; a map that needs more than max_pool_bytes for that gets
 * MemoryLimitError, saying how much, before the work.
 */
std::string encodeBt(const FastOctTree& tree, std::size_t max_pool_bytes = kDefaultMaxPoolBytes);

/** Writes a .bt file atomically. Throws as encodeBt, and std::runtime_error on I/O errors. */
void saveBt(const FastOctTree& tree, const std::string& path,
            std::size_t max_pool_bytes = kDefaultMaxPoolBytes);

/**
 * The map in .bt bytes, with OctoMap's cells: its resolution from the header, the origin from the options.
 * Every occupancy tree type (OcTree, ColorOcTree, OcTreeStamped) writes the same .bt body under its own id;
 * the reader takes any, as OctoMap does. Throws FormatError, prefixed with `name`, for a malformed file (bad
 * header, truncated or excess body, a node count that disagrees with the header), std::invalid_argument for
 * an origin off OctoMap's grid, and MemoryLimitError beyond the cap.
 */
FastOctTree decodeBt(const char* bytes, std::size_t size, const std::string& name = "<memory>",
                     const OctoMapImportOptions& options = {});

/** Reads a .bt file; throws as decodeBt, and std::runtime_error when it cannot be read. */
FastOctTree loadBt(const std::string& path, const OctoMapImportOptions& options = {});

/**
 * The .ot bytes of a tree, as OctoMap 1.9's OcTree::write writes them: every node's float log-odds (an inner
 * node's is its children's maximum) and its child mask, in pre-order. OctoMap reads the same value in every
 * leaf that this map holds in every cell. Throws as encodeBt.
 */
std::string encodeOt(const FastOctTree& tree, std::size_t max_pool_bytes = kDefaultMaxPoolBytes);

/** Writes a .ot file atomically. Throws as encodeOt, and std::runtime_error on I/O errors. */
void saveOt(const FastOctTree& tree, const std::string& path,
            std::size_t max_pool_bytes = kDefaultMaxPoolBytes);

/**
 * The map in .ot bytes, from the trees OcTree, OcTreeStamped and ColorOcTree (its colours are dropped).
 * Every leaf's log-odds is kept exactly; the options' sensor model thresholds it (occupied at 0 and above,
 * by default) and says which values are settled. Throws FormatError, prefixed with `name`, for a malformed
 * file (bad header, another tree type, truncated or excess body, a log-odds that is not finite, a node
 * count that disagrees with the header), std::invalid_argument for an origin off OctoMap's grid, and
 * MemoryLimitError beyond the cap (also, at once, for a pruned leaf between the clamps whose cells would
 * need more).
 */
FastOctTree decodeOt(const char* bytes, std::size_t size, const std::string& name = "<memory>",
                     const OctoMapImportOptions& options = {});

/** Reads a .ot file; throws as decodeOt, and std::runtime_error when it cannot be read. */
FastOctTree loadOt(const std::string& path, const OctoMapImportOptions& options = {});

}  // namespace io
}  // namespace fot
}  // namespace pcl
