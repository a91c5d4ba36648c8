#pragma once
// Private to the library: what OctoMap's .bt and .ot files share, their text header and their key grid.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/octomap.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace io {
namespace octomap_format {

constexpr unsigned kDepth = 16;  // OctoMap's tree depth: 65536 cells per axis
constexpr std::int32_t kCentre = 32768;

// OctoMap's cells are read into a staging tree whose tree coordinates are OctoMap's keys plus 0x2AAA0000, so
// that its nodes are exactly OctoMap's: the level-16 cube at kStagingRoot is OctoMap's root. Its keys are
// OctoMap's less 32768: those of a map with origin 0 (see tree_coord).
constexpr std::uint32_t kStagingBase = 0x2AAA0000u;
const TreeCoord kStagingRoot(kStagingBase, kStagingBase, kStagingBase);

/** The origin in whole cells from coordinate 0; throws std::invalid_argument if it is not on OctoMap's grid.
 */
std::int32_t cellsFromZero(double origin, double res, const char* axis);

/** The shortest decimal that reads back as the same double: the header's resolution. */
std::string exactDecimal(double v);

/** OctoMap's header lines before the tree: first line, comment, id, size, res, data. */
std::string headerText(const char* first_line, std::uint64_t size, double res);

struct Header {
  std::string id;      ///< the tree type; OctoMap's legacy "1" reads as "OcTree"
  std::uint64_t size;  ///< nodes, leaves included
  double resolution;   ///< positive and finite
  std::size_t body;    ///< where the tree's bytes start
};

/**
 * Reads the text header: `first_line` (matched by prefix, as OctoMap does), then keyword lines up to "data".
 * Throws FormatError starting with `what_file` ("'name' is not a valid OctoMap .bt file").
 */
Header readHeader(const char* bytes, std::size_t size, const char* first_line, const std::string& what_file);

/**
 * The tree in OctoMap's grid: the map itself at origin 0, else a copy moved there; its cells must lie
 * within OctoMap's cube (std::invalid_argument otherwise).
 */
FastOctTree const* toStaging(const FastOctTree& tree, std::optional<FastOctTree>& moved,
                             std::size_t max_pool_bytes);

/** The map a staging tree holds, moved to the caller's origin, within the caller's memory cap. */
FastOctTree placeStaging(FastOctTree staging, double res, const OctoMapImportOptions& options);

/**
 * Reads the tree after the header into a staging tree, with the reader make_reader(body, size, staging)
 * gives (node(depth, corner) from the root; nodes(); left()); checks the header's node count and that
 * nothing follows; and places the map. An origin off the grid fails before the work.
 */
template <typename MakeReader>
FastOctTree readBody(const char* bytes, std::size_t size, const Header& h,
                     const OctoMapImportOptions& options, const std::string& what_file,
                     MakeReader&& make_reader) {
  cellsFromZero(options.origin[0], h.resolution, "x");
  cellsFromZero(options.origin[1], h.resolution, "y");
  cellsFromZero(options.origin[2], h.resolution, "z");
  FastOctTree staging(h.resolution);
  staging.setSensorModel(options.sensor_model);
  staging.setMaxMemoryBytes(options.max_pool_bytes);
  auto reader = make_reader(reinterpret_cast<const unsigned char*>(bytes) + h.body, size - h.body, staging);
  std::uint64_t nodes = 0;
  if (h.size > 0) {
    reader.node(0, kStagingRoot);
    nodes = reader.nodes();
  }
  if (nodes != h.size)
    throw FormatError(what_file + ": the tree has " + std::to_string(nodes) + " nodes, the header says " +
                      std::to_string(h.size));
  if (reader.left() != 0)
    throw FormatError(what_file + ": " + std::to_string(reader.left()) + " bytes follow the tree");
  return placeStaging(std::move(staging), h.resolution, options);
}

}  // namespace octomap_format
}  // namespace io
}  // namespace fot
}  // namespace pcl
