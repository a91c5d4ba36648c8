#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace io {

/** A file that is not a valid map. The message names the file and what is wrong with it. */
class FormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/**
 * The .fot format version this build writes: version 2 with the update rule, the sensor model and the
 * log-odds of unsettled leaves. It reads versions 2 (binary maps, OctoMap's default sensor model) and 1,
 * whose tree coordinates were keys + 0x2AAAAAAA (see tree_coord): such a map is moved into today's nodes on
 * loading, within the pool cap.
 */
constexpr unsigned kFotVersion = 3;
/** By default a loader refuses pools (with their values) beyond 4 GiB rather than allocate whatever a file
 * claims. */
constexpr std::size_t kDefaultMaxPoolBytes = std::size_t(4) << 30;

/**
 * The .fot bytes of a tree (doc/file_format.md): a little-endian header with the magic, version, grid,
 * root, counts, update rule and sensor model; the canonical pool and its values
 * (FastOctTree::canonicalPool); a CRC-32 of everything before it.
 * Equal trees give equal bytes.
 */
std::string encodeFot(const FastOctTree& tree);

/**
 * The tree in .fot bytes. Validates everything before it allocates the pool, and the structure before it
 * builds the tree (see FastOctTree::fromCanonicalPool); throws FormatError, prefixed with `name`.
 */
FastOctTree decodeFot(const char* bytes, std::size_t size, const std::string& name = "<memory>",
                      std::size_t max_pool_bytes = kDefaultMaxPoolBytes);

/** Writes the tree atomically (a temporary file, then a rename). Throws std::runtime_error on I/O errors. */
void saveFot(const FastOctTree& tree, const std::string& path);

/** Reads a .fot file; throws FormatError for a bad file and std::runtime_error when it cannot be read. */
FastOctTree loadFot(const std::string& path, std::size_t max_pool_bytes = kDefaultMaxPoolBytes);

}  // namespace io
}  // namespace fot
}  // namespace pcl
