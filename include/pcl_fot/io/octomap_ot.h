#pragma once

#include <cstddef>
#include <string>

#include <pcl_fot/fast_oct_tree.h>
#include <pcl_fot/io/octomap_bt.h>

namespace pcl {
namespace fot {
namespace io {

/**
 * OctoMap's full .ot format, read without the OctoMap library: the trees OcTree, OcTreeStamped and
 * ColorOcTree (its colours are dropped). Every leaf becomes free or occupied as OctoMap's isNodeOccupied
 * says with its default threshold, probability 0.5: occupied when its log-odds is at least 0. The grid is
 * OctoMap's, as for .bt (see octomap_bt.h), and the options are the same.
 */

/**
 * The map in .ot bytes. Throws FormatError, prefixed with `name`, for a malformed file (bad header, another
 * tree type, truncated or excess body, a log-odds that is not a number, a node count that disagrees with
 * the header), std::invalid_argument for an origin off OctoMap's grid, and MemoryLimitError beyond the cap.
 */
FastOctTree decodeOt(const char* bytes, std::size_t size, const std::string& name = "<memory>",
                     const BtImportOptions& options = {});

/** Reads a .ot file; throws as decodeOt, and std::runtime_error when it cannot be read. */
FastOctTree loadOt(const std::string& path, const BtImportOptions& options = {});

}  // namespace io
}  // namespace fot
}  // namespace pcl
